"""The effort each actuator carries: learnt from normal CSV flights written here (a
controller that shares the load unequally, as a real one does), judged on a flight whose
motor 3 is driven harder from 15 s; refusals with too few logs; thresholds to a budget; the
real CrazyPAD flights where ../shared/data holds them."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_json
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_errors import ProfileError
from models.chi_square import largest_spread_factor, lower_quantile
from models.student_t import quantile

pytestmark = pytest.mark.slow    # trains models or simulates fleets

runner = CliRunner()
SHARES = np.array([1.07, 0.87, 1.13, 0.93])
CRAZYPAD = SHARED_DATA / "crazypad"
RATE_HZ = 100


def write_flight(path: Path, seed: int, seconds: float = 30.0, weak_from_s: float | None = None,
                 extra: float = 0.15) -> Path:
    """A Crazyflie-style CSV flight: on the ground 2 s, then hovering and climbing, the
    controller's noise on every motor; from ``weak_from_s`` motor 3 carries ``extra`` more."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, seconds, 1 / RATE_HZ)
    level = np.where(t < 2.0, 0.0, 0.6 + 0.05 * np.sin(t / 3.0))
    shares = np.tile(SHARES * (1 + rng.normal(0, 0.004, 4)), (len(t), 1))
    if weak_from_s is not None:
        shares[t >= weak_from_s, 2] *= 1 + extra
    shares /= shares.mean(axis=1, keepdims=True)
    motors = level[:, None] * shares * (1 + rng.normal(0, 0.03, (len(t), 4)))
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["time_us", "motor_m1", "motor_m2", "motor_m3", "motor_m4",
                         "stateEstimate_vx", "stateEstimate_vy", "stateEstimate_vz"])
        for k, time in enumerate(t):
            writer.writerow([int(5e6 + time * 1e6), *(int(v * 65535) for v in motors[k]),
                             *rng.normal(0, 0.05, 3).round(4)])
    return path


def invoke(*arguments: str) -> tuple[int, str]:
    result = runner.invoke(app, list(arguments))
    assert "unexpected" not in result.output and "Traceback" not in result.output
    return result.exit_code, result.output


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("flights")
    for seed in range(5):
        write_flight(folder / f"normal_{seed}.csv", seed)
    write_flight(folder / "later_normal.csv", 50)
    write_flight(folder / "weak_motor_3.csv", 51, weak_from_s=15.0)
    write_flight(folder / "weak_late.csv", 52, weak_from_s=24.0)
    return folder


@pytest.fixture(scope="module")
def model(flights: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    target = tmp_path_factory.mktemp("model") / "cf"
    code, output = invoke("train", *(str(flights / f"normal_{s}.csv") for s in range(5)),
                          "--profile", "crazyflie", "--output", str(target),
                          "--iterations-scale", "0.02", "--hidden", "8",
                          # the effort is judged whichever predictor reads the motion
                          # (the least-squares one alone: the network is then not trained)
                          "--predictor", "linear")
    assert code == 0, output
    return target


def test_student_t_quantiles_match_the_tables():
    for p, dof, table in ((0.975, 1, 12.706), (0.975, 5, 2.571), (0.995, 6, 3.707),
                          (0.999, 30, 3.385), (0.975, 1000, 1.962)):
        assert quantile(p, dof) == pytest.approx(table, abs=2e-3)


def test_chi_square_lower_quantiles_match_the_tables():
    for p, dof, table in ((0.05, 2, 0.1026), (0.05, 6, 1.635), (0.01, 1, 0.000157),
                          (0.025, 10, 3.247), (0.05, 45, 30.612)):
        assert lower_quantile(p, dof) == pytest.approx(table, rel=2e-3)
    # A spread estimated on 6 degrees of freedom may be 1.92 times smaller than the truth.
    assert largest_spread_factor(6, 0.95) == pytest.approx(1.915, abs=2e-3)


def test_train_keeps_a_model_that_judges_only_the_effort(model: Path):
    entry = json.loads((model / "model.json").read_text())["effort"]
    group = entry["groups"][0]
    assert group["members"] == ["motor_1", "motor_2", "motor_3", "motor_4"]
    assert len(group["logs"]) == 5
    share = np.mean(np.atleast_2d(group["normal"]["share"]), axis=0)
    assert share == pytest.approx(SHARES / SHARES.mean(), abs=0.01)
    assert group["normal"]["threshold_z"] > 2


def test_a_motor_driven_harder_is_named_with_its_onset(flights: Path, model: Path,
                                                       tmp_path: Path):
    code, output = invoke("diagnose", str(flights / "weak_motor_3.csv"), "--profile",
                          "crazyflie", "--model", str(model), "--json", str(tmp_path / "d.json"),
                          "--pdf", str(tmp_path / "d.pdf"))
    assert code == 1, output
    report = json.loads((tmp_path / "d.json").read_text())
    assert report["component"] == "motor_3"
    actuators = report["actuators"]
    assert [n for n, a in actuators["shares"].items() if a["driven_harder"]] == ["motor_3"]
    assert actuators["signatures"][0]["actuator"] == "motor_3"
    assert actuators["signatures"][0]["match"] > 0.9
    assert actuators["shares"]["motor_3"]["departure"] > 0.03
    # The others fell: the normalisation, never a second fault.
    assert all(a["departure"] < 0 for n, a in actuators["shares"].items() if n != "motor_3")
    # It began at 15 s: dated within 2 s, seen within 5 s (against the flight's own start).
    assert 13.0 <= report["onset_s"] <= 17.0
    assert max(15.0, report["onset_s"]) <= report["detected_at_s"] <= 20.0
    # The error it states of the onset holds the true one, and is said.
    error = actuators["onset_error_s"]
    assert 0 < error < 5.0 and abs(actuators["onset_s"] - 15.0) <= error
    assert f"it began at ~{actuators['onset_s']:.1f} s (give or take {error:.1f} s)" in (
        actuators["summary"])
    assert "carries" in output and "more of the effort" in output
    # The audit table carries the effort's own onset and detection.
    from auvdiag_cli.audit.record import AuditRecord
    from auvdiag_cli.audit.table import table_row

    row = table_row(AuditRecord.from_report({**report, "log": "weak_motor_3.csv"}))
    assert (row["effort_onset_s"], row["effort_detected_at_s"]) == (
        actuators["onset_s"], actuators["alarm_s"])
    assert 13.0 <= row["effort_onset_s"] < row["effort_detected_at_s"] <= 20.0
    # The profile's rotors are worded as rotors, not a marine vehicle's thrusters.
    assert "a damaged propeller or a weak motor" in actuators["summary"]
    assert "fouled" not in actuators["summary"]
    from pypdf import PdfReader

    text = "".join(page.extract_text() for page in PdfReader(tmp_path / "d.pdf").pages)
    assert "Share of the group's effort" in text and "motor_3 (driven harder)" in text
    assert "one weak actuator shows over this log from +" in text
    # Named from the effort, not from a row of the pattern table: the report says so, and
    # not that the verdict names no component.
    assert report["case"] is None and "named from the other evidence" in text
    assert "names no component" not in text


def test_a_weakness_in_the_last_windows_is_dated_where_it_began(flights: Path, model: Path):
    """Motor 3 driven harder from 24 s of a 30 s flight: less than two of its 4.7 s windows
    before the end. Its onset is placed there, within the error stated, not at the last
    start the test tried."""
    code, report = diagnose_json(flights / "weak_late.csv", "--profile", "crazyflie",
                                 "--model", str(model))
    assert code == 1, report
    actuators = report["actuators"]
    assert actuators["named"] == ["motor_3"]
    error = actuators["onset_error_s"]
    assert abs(actuators["onset_s"] - 24.0) <= error < 5.0
    assert 24.0 <= report["detected_at_s"] <= 29.0


def test_a_normal_flight_is_normal(flights: Path, model: Path):
    code, report = diagnose_json(flights / "later_normal.csv", "--profile", "crazyflie",
                                 "--model", str(model))
    assert code == 0, report
    actuators = report["actuators"]
    assert actuators["judged"] and not actuators["named"]
    assert all(a["over_threshold"] < 1 for a in actuators["shares"].values())
    # What these normal flights let it see: a rise of one motor's share larger than any
    # this flight shows, said in the summary and per motor.
    rises = [a["smallest_rise_shown"] for a in actuators["shares"].values()]
    assert all(r > max(a["departure"] for a in actuators["shares"].values()) for r in rises)
    assert "one weak actuator shows over this log once it carries about" in (
        actuators["summary"])


def test_too_few_normal_logs_or_too_little_steady_time_are_not_judged(flights: Path,
                                                                       model: Path,
                                                                       tmp_path: Path):
    code, output = invoke("train", str(flights / "normal_0.csv"), str(flights / "normal_1.csv"),
                          "--profile", "crazyflie", "--output", str(tmp_path / "m"),
                          "--iterations-scale", "0.02", "--hidden", "8",
                          "--predictor", "linear")
    assert code == 1
    assert "needs 3 normal logs" in output and not (tmp_path / "m").exists()
    short = write_flight(tmp_path / "short.csv", 7, seconds=4.0)
    _, report = diagnose_json(short, "--profile", "crazyflie", "--model", str(model))
    shares = report["actuators"]["shares"]
    assert "too little steady effort in this log" in shares["motor_1"]["not_judged"]
    assert report["verdict"] == "undetermined"


def test_calibrate_sets_the_threshold_for_a_false_alarm_budget(flights: Path, model: Path,
                                                               tmp_path: Path):
    def threshold(directory: Path) -> float:
        entry = json.loads((directory / "model.json").read_text())["effort"]
        return float(entry["groups"][0]["normal"]["threshold_z"])

    strict, loose = tmp_path / "strict", tmp_path / "loose"
    for target, rate in ((strict, "0.001"), (loose, "0.1")):
        code, output = invoke("calibrate", "--model", str(model), "--output", str(target),
                              "--profile", "crazyflie", str(flights / "later_normal.csv"),
                              "--false-alarm-rate", rate)
        assert code == 0, output
        assert "6 normal logs" in output
    assert threshold(strict) > threshold(model) > threshold(loose)
    code, output = invoke("calibrate", "--model", str(model), "--output", str(tmp_path / "x"),
                          "--profile", "crazyflie", str(flights / "later_normal.csv"),
                          "--false-alarm-rate", "0.7")
    assert code == 2 and "--false-alarm-rate" in output


def test_the_audit_table_and_the_trend_carry_the_shares():
    from auvdiag_cli.audit.record import AuditRecord
    from auvdiag_cli.audit.table import table_row

    record = AuditRecord.from_report({
        "log": "fleet/cf/a.csv", "verdict": "fault", "actuators": {
            "summary": "motor_3 is driven harder", "shares": {
                name: {"group": "rotors", "component": name, "over_threshold": ratio,
                       "driven_harder": harder}
                for name, ratio, harder in (("motor_1", -0.2, False), ("motor_3", 1.4, True),
                                            ("motor_4", None, False))}}})
    row = table_row(record)
    assert (row["driven_harder"], row["worst_effort_actuator"], row["worst_effort_ratio"]) == \
        ("motor_3", "motor_3", 1.4)
    assert record.margins == {"motor_1 share": -0.2, "motor_3 share": 1.4}
    assert record.fleet_vehicle == "cf"          # no vehicle assigned: the folder


def test_why_a_profile_without_groups_judges_no_effort_is_its_own():
    from auvdiag_cli.jobs.effort import learn_effort_model
    from auvdiag_cli.vehicle.profile import load_profile
    from models.card import Refused

    # Thrusters not grouped: the profile could group them.
    refused, _ = learn_effort_model([], load_profile(Path("twin_burger")))
    assert isinstance(refused, Refused) and "add [[effort]] groups" in refused.reason
    # Driven by set points: no actuator output is read, so no group could be added.
    refused, _ = learn_effort_model([], load_profile(Path("arduplane_carbonz")))
    assert isinstance(refused, Refused) and "set points" in refused.reason
    assert "add [[effort]]" not in refused.reason


def test_effort_groups_in_a_profile_are_checked(tmp_path: Path):
    from auvdiag_cli.vehicle.profile import load_profile, profile_text

    text, _ = profile_text(Path("crazyflie"))
    for bad, words in (('actuators = ["motor_1", "motor_9"]', "two or more distinct"),
                       ('actuators = ["motor_1"]', "two or more distinct"),
                       ('actuators = ["motor_1", "motor_2"]\nfactors = [1.0]', "one non-zero")):
        path = tmp_path / "p.toml"
        path.write_text(text.replace(
            'actuators = ["motor_1", "motor_2", "motor_3", "motor_4"]', bad))
        with pytest.raises(ProfileError, match=words):
            load_profile(path)


def test_init_profile_proposes_groups_of_alike_commands():
    from adapters.signals import FieldSource
    from auvdiag_cli.jobs.draft_groups import effort_groups
    from auvdiag_cli.jobs.draft_text import Proposal

    def command(name: str, level: float, two_way: bool) -> Proposal:
        return Proposal(name, FieldSource("RCOU", name), "1", "", level=level, two_way=two_way)

    rotors = [command(f"c{k}", 0.55 + 0.02 * k, False) for k in range(4)]
    assert effort_groups(rotors, set()) == [["c0", "c1", "c2", "c3"]]
    mixed = [*rotors[:2], command("gimbal", 0.05, False), command("t1", 0.3, True),
             command("t2", 0.35, True)]
    assert effort_groups(mixed, set()) == [["c0", "c1"], ["t1", "t2"]]
    assert effort_groups(rotors, {frozenset(["c0", "c1", "c2", "c3"])}) == []
    # Logged side by side, thrusters at like levels that do not move together are two jobs
    # (a ROV's horizontal and vertical thrusters); a pair that moves against each other is
    # one (a differential pair).
    rng = np.random.default_rng(0)
    surge, heave = rng.normal(size=(2, 500))
    thrusters = [command(f"t{k}", 0.3 + 0.01 * k, True) for k in range(4)]
    logged = [surge, -surge + 0.3 * rng.normal(size=500), heave, heave]
    assert effort_groups(thrusters, set(), logged) == [["t0", "t1"], ["t2", "t3"]]


@pytest.mark.shared_data("crazypad/labels.csv")
def test_crazypad_cut_propeller_found_and_named_without_false_alarms():
    from auvdiag_cli.engine.effort_check import check_effort
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.jobs.effort import effort_log
    from auvdiag_cli.jobs.relate import relation_log
    from auvdiag_cli.vehicle.profile import load_profile
    from models.effort_model import learn_effort

    profile = load_profile(Path("crazyflie"))

    def read(folder: str) -> list:
        return [relation_log(ingest(p, profile), profile)
                for p in sorted((CRAZYPAD / "E8" / folder).glob("*.csv"))]

    def judged(model, log) -> tuple[str, ...]:
        check = check_effort(model, profile, log.commands, log.usable,
                             profile.dt_s * np.arange(len(log.commands)))
        return check.named

    normal = read("normal_flight")
    for k, log in enumerate(normal):
        others, _ = learn_effort(profile.effort_groups,
                                 [effort_log(g, profile) for i, g in enumerate(normal) if i != k],
                                 profile.dt_s)
        assert judged(others, log) == ()
    model, _ = learn_effort(profile.effort_groups, [effort_log(g, profile) for g in normal],
                            profile.dt_s)
    for log in read("cut_propeller_M3_3.5mm_3.5mm_40mm") + read("cut_propeller_M3_4mm_4mm_39mm"):
        assert judged(model, log) == ("motor_3",)


@pytest.mark.parametrize(("vehicle", "weak", "component", "member"), [
    ("arducopter_quad", "mission-motor-2-weak", "motor_2", 1),
    # A vectored ROV holding its track and its level: a weak horizontal thruster is driven
    # harder alone, not with its diagonal partner (motor 3), a weak vertical one alone too.
    ("bluerov2", "mission-thruster-1-weak", "thruster_1", 0),
    ("bluerov2", "mission-thruster-6-weak", "thruster_6", 5),
])
def test_a_simulated_vehicle_names_its_weak_actuator(tmp_path: Path, vehicle: str, weak: str,
                                                     component: str, member: int):
    """The profile flown by its own controller and written as real .tlog files: learnt from
    normal missions, a normal mission of another seed is not flagged, and an actuator keeping
    half its thrust from 60 s is named alone, its command risen by about 1/sqrt(0.5) where
    its group's others move far less."""
    from auvdiag_cli.engine.effort_check import check_effort
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.jobs.effort import effort_log
    from auvdiag_cli.jobs.relate import relation_log
    from auvdiag_cli.vehicle.profile import load_profile
    from models.effort_model import learn_effort

    profile = load_profile(Path(vehicle))

    def flown(scenario: str, seed: int) -> Path:
        path = tmp_path / f"{scenario}-{seed}.tlog"
        code, output = invoke("simulate", scenario, "--profile", vehicle, "--format", "tlog",
                              "--seed", str(seed), "-o", str(path))
        assert code == 0, output
        return path

    def logged(path: Path):  # type: ignore[no-untyped-def]
        return relation_log(ingest(path, profile), profile)

    normal = [logged(flown(name, seed)) for seed in (1, 2)
              for name in ("paper-normal", "mission-ccw", "mission-fast-cw")]
    model, why = learn_effort(profile.effort_groups, [effort_log(g, profile) for g in normal],
                              profile.dt_s)
    assert model is not None, why

    def judged(path: Path):  # type: ignore[no-untyped-def]
        log = logged(path)
        return log, check_effort(model, profile, log.commands, log.usable,
                                 profile.dt_s * np.arange(len(log.commands)))

    _, calm = judged(flown("mission-large-cw", 7))
    assert not calm.suspects
    log, found = judged(flown(weak, 8))
    assert found.named == (component,)
    group = next(g for g in profile.effort_groups if profile.commands[member].name in g.members)
    columns = [i for i, c in enumerate(profile.commands) if c.name in group.members]
    after = np.abs(log.commands[round(75 / profile.dt_s):, columns]).mean(axis=0)
    before = np.abs(log.commands[round(20 / profile.dt_s):round(55 / profile.dt_s),
                                 columns]).mean(axis=0)
    risen = after / before
    own = columns.index(member)
    assert risen[own] > 1.25 and np.all(np.delete(risen, own) < risen[own] - 0.15)


def test_a_rotor_lost_mid_flight_is_named_by_its_effort_when_no_replay_explains_it(
        tmp_path: Path):
    """A quadrotor whose motor dies cannot be replayed by any single fault the model knows
    (it loses control), but the effort its rotors carry matches that motor's weakness
    alone: it is named, from the DataFlash logs the simulator writes. A normal flight of
    another seed is normal."""
    from auvdiag_cli import api

    def flown(scenario: str, seed: int) -> Path:
        path = tmp_path / f"{scenario}-{seed}.bin"
        code, output = invoke("simulate", scenario, "--profile", "arducopter_quad",
                              "--format", "bin", "--seed", str(seed), "-o", str(path))
        assert code == 0, output
        return path

    profile = api.load_profile("arducopter_quad")
    normal = [flown(name, 5) for name in ("paper-normal", "mission-ccw", "mission-large-cw")]
    trained = api.train(normal, profile, tmp_path / "model", options=api.TrainOptions(
        iterations_scale=0.05, hidden=8, keep_unskilled=True,
        predictors=("linear", "linear-replay")), progress=lambda _: None)
    # The commands against the motion cannot tell the rotors apart; train says what can,
    # and which form of the relation it kept: the motion learnt from each rotor's thrust
    # would tell them apart, but three missions let it judge no loss below its floor.
    from auvdiag_cli.reports.training import training_lines
    lines = training_lines(trained, {}, profile)
    assert ("  motor_1 and motor_2 and motor_3 and motor_4 act alike on the vehicle: this "
            "check names a weakness as either (the effort shares of rotors tell them apart)"
            in lines), lines
    assert any(line.startswith("  kept: the commands learnt from the motion judges a loss of "
                               "thrust from ") for line in lines), lines
    # The model keeps the change test's largest statistics on the three it was trained on,
    # as strict JSON (a statistic never judged is null, not NaN).
    def no_constants(name: str) -> float:
        raise AssertionError(f"{name} in model.json")

    document = json.loads((tmp_path / "model" / "model.json").read_text(),
                          parse_constant=no_constants)
    kept = document["change_training"]["logs"]
    assert [entry["log"] for entry in kept] == [path.name for path in normal]
    assert all(entry["peaks"]["sum"] for entry in kept)
    # And how long it judged each signal there, which calibrate adds up.
    assert all(min(entry["judged_s"].values()) > 30.0 for entry in kept)
    model = api.load_model(tmp_path / "model", profile)
    # Two more normal flights set the thresholds, from blocks of them (too few for a law
    # of their peaks).
    calibration_logs = [flown(name, 6) for name in ("mission-sprint-ccw", "mission-fast-cw")]
    calibration = api.calibrate(calibration_logs, profile, model, options=api.CalibrateOptions(
        budget=api.FalseAlarmBudget(0.01)))
    assert calibration.budget is not None and all(f.by_block for f in calibration.budget.fits
                                                  if f.judge.kind == "g")
    # The change test's thresholds rest on the two logs' peaks and the three the model was
    # trained on (it keeps them): a law of five; the commands' keep the margin rule.
    assert any(f.judge.kind == "change" and len(f.judge.more) == 3 and not f.by_block
               for f in calibration.budget.fits)
    assert any("2 calibration log(s): the commands' thresholds (the change test's count the "
               "logs trained on) take the margin rule" in warning
               for warning in calibration.warnings)
    assert calibration.change_trained_on == tuple(path.name for path in normal)
    # The replay's thresholds rest on the two logs the model was not trained on: too few
    # to settle them (`engine.settled`).
    assert model.card.calibration_unseen_logs == 2
    # The change test's rest on five, which settle them (`engine.slight_change`).
    assert model.card.change_logs == 5
    # Five logs are too few to tell how far normal operation goes each way: both ways alike.
    assert not model.card.change_way_scales
    from auvdiag_cli.reports.training import calibration_lines

    assert any("largest on these logs and the 3 trained on -> threshold" in line
               for line in calibration_lines(calibration))
    # A log trained on and calibrated with counts once.
    again = api.calibrate([*normal[:1], *calibration_logs], profile,
                          api.load_model(tmp_path / "model", profile),
                          options=api.CalibrateOptions(budget=api.FalseAlarmBudget(0.01)))
    assert again.change_trained_on == tuple(path.name for path in normal[1:])
    # Peaks kept by a model trained before the test judged a window every step, or each way
    # apart, are another statistic's: not counted, and calibrate says so.
    assert document["change_training"]["each_way"] is True
    for earlier in ("stride_steps", "each_way"):
        value = document["change_training"].pop(earlier)
        (tmp_path / "model" / "model.json").write_text(json.dumps(document))
        stale = api.calibrate(calibration_logs, profile,
                              api.load_model(tmp_path / "model", profile))
        assert stale.change_trained_on == ()
        assert any("measured by an earlier form of the test" in warning
                   and "for the 3 log(s)" in warning for warning in stale.warnings)
        document["change_training"][earlier] = value
    dead = api.diagnose(flown("mission-motor-3-dead", 7), profile, model)
    assert dead.verdict.value == "fault" and dead.component == "motor_3"
    assert any("no single-component fault explains it" in note
               and "its shares match motor_3 weak alone" in note for note in dead.notes)
    assert dead.onset_s == pytest.approx(60.0, abs=3.0)
    calm = api.diagnose(flown("paper-normal", 7), profile, model)
    assert calm.verdict.value == "normal"
