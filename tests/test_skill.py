"""Models that know what they know: skill against naive predictors decides which signals are
judged; a finite prediction horizon still finds failed sensors; spikes and the replay's
start-up raise no alarm."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pypdf
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from models.skill import MIN_SKILL, HorizonScore, SignalSkill, choose_horizon
from models.store import default_model_dir

runner = CliRunner()


def test_skill_is_measured_against_the_better_naive_predictor():
    s = SignalSkill(0.02, {"hold": 0.10, "mean": 0.05, "linear": 0.03})
    assert s.best_naive == "mean" and s.skill == pytest.approx(0.6)
    assert s.versus_linear == pytest.approx(1 / 3) and s.judged
    assert not SignalSkill(0.04, {"hold": 0.10, "mean": 0.05, "linear": 0.01}).judged
    flat = SignalSkill(0.01, {"hold": 0.0, "mean": 0.0, "linear": 0.0})
    assert flat.skill == -math.inf and not flat.judged        # a signal that never moves
    assert pytest.approx(1 - 1 / 1.5) == MIN_SKILL


def _horizon(horizon_s: float | None, **skills: float) -> HorizonScore:
    return HorizonScore(horizon_s, {name: SignalSkill(1.0 - skill, {
        "hold": 1.0, "mean": 1.0, "linear": 1.0}) for name, skill in skills.items()})


def test_the_longest_horizon_that_judges_the_most_signals_with_a_margin_is_chosen():
    # The free run judges both signals, but yaw only just: 8 s judges both clearly.
    scores = [_horizon(None, depth=0.49, yaw=0.34), _horizon(8.0, depth=0.61, yaw=0.36),
              _horizon(4.0, depth=0.60, yaw=0.42), _horizon(2.0, depth=0.45, yaw=0.25)]
    assert choose_horizon(scores).horizon_s == 8.0
    # Both clear the bar well at the free run: the longest horizon is kept.
    scores[0] = _horizon(None, depth=0.49, yaw=0.40)
    assert choose_horizon(scores).horizon_s is None
    # A signal judged only at a short horizon still wins that horizon.
    assert choose_horizon([_horizon(None, depth=0.5, yaw=0.2),
                           _horizon(4.0, depth=0.6, yaw=0.34)]).horizon_s == 4.0


def test_the_skill_table_says_which_signals_only_the_change_test_judges():
    from auvdiag_cli.reports.training import OWN_LOG_ONLY, skill_lines

    score = _horizon(None, roll=0.8, climb=0.1)
    rows = skill_lines([score], score, own_log_only={"roll"})
    # Skilled as it is, the replay does not judge roll: the profile leaves it to the
    # change test, and the table says so rather than "yes".
    assert rows[-3].split()[0] == "roll" and rows[-3].endswith(OWN_LOG_ONLY)
    assert rows[-2].split()[0] == "climb" and rows[-2].endswith("NO: not judged (the model "
                                                                 "cannot predict it)")
    assert rows[-1].startswith(f"  {OWN_LOG_ONLY}: the profile judges it only against")
    plain = skill_lines([score], score)
    assert plain[-2].endswith("yes") and not any(OWN_LOG_ONLY in row for row in plain)


def _noise_log(path: Path, seed: int, seconds: float = 240.0) -> Path:
    """A Twin-Burger CSV log whose sensors are noise unrelated to its commands."""
    rng = np.random.default_rng(seed)
    steps = int(seconds * 10)
    time_s = np.arange(steps) * 0.1
    commands = np.repeat(rng.uniform(-0.8, 0.8, (steps // 50 + 1, 2)), 50, axis=0)[:steps]
    drift = np.cumsum(rng.normal(0, 0.01, (steps, 2)), axis=0)
    sensors = 0.1 * np.tanh(drift) + rng.normal(0, 0.03, (steps, 2))
    pd.DataFrame({"time_s": time_s, "thruster_0": commands[:, 0],
                  "thruster_1": commands[:, 1], "flow_mps": sensors[:, 0],
                  "yaw_rate_rps": sensors[:, 1], "sequence": ""}).to_csv(path, index=False)
    return path


@pytest.mark.slow
def test_a_model_trained_on_noise_has_no_skill_and_judges_nothing(tmp_path):
    logs = [str(_noise_log(tmp_path / f"noise{i}.csv", i)) for i in range(2)]
    model = tmp_path / "noise-model"
    # Two of the four predictors: the other two refine these at the cost of a second
    # network and a replay fit, and noise teaches none of them anything.
    options = ["--iterations-scale", "0.03", "--hidden", "8", "--horizon", "auto",
               "--predictor", "network", "--predictor", "linear"]
    refused = runner.invoke(app, ["train", logs[0], "--output", str(model), *options])
    assert refused.exit_code == 1, refused.output
    assert "NOT written" in refused.stdout and "no signal has skill" in refused.output
    assert "NO: not judged (the model cannot predict it)" in refused.stdout
    assert not model.exists()

    kept = runner.invoke(app, ["train", logs[0], "--output", str(model), "--keep-unskilled",
                               *options])
    assert kept.exit_code == 1 and (model / "model.json").is_file(), kept.output
    meta = json.loads((model / "model.json").read_text())
    assert meta["heldout_error"]["logs"] == ["noise0.csv (last 20%)"]    # one log is enough
    assert not any(s["judged"] for s in meta["skill"]["signals"].values())

    code, report = diagnose_json(Path(logs[1]), "--model", str(model))
    assert code == 0 and report["verdict"] == "undetermined"
    assert set(report["not_judged"]) == {"flow", "yaw_rate"}
    assert report["detected_at_s"] is None and not any(report["b"].values())
    text = runner.invoke(app, ["diagnose", logs[1], "--model", str(model)]).stdout
    assert "UNDETERMINED" in text and "flow: not judged (the model cannot predict it)" in text


def _shipped_copy(target: Path, **changes: object) -> Path:
    """The shipped Twin-Burger model with ``changes`` made to its model.json."""
    target.mkdir()
    for file in default_model_dir().iterdir():
        (target / file.name).write_bytes(file.read_bytes())
    meta = json.loads((target / "model.json").read_text())
    meta.update(changes)
    (target / "model.json").write_text(json.dumps(meta))
    return target


def _unskilled_copy(target: Path, signal: str, relations: bool = False) -> Path:
    """The shipped model, with ``signal`` marked as one it cannot predict; without its
    command relations unless asked (they judge the commands, not the signal)."""
    skill = json.loads((default_model_dir() / "model.json").read_text())["skill"]
    skill["signals"][signal].update(skill=0.05, judged=False)
    if relations:
        return _shipped_copy(target, skill=skill)
    return _shipped_copy(target, skill=skill,
                         command_relations={"refused": "left out of this copy"})


@pytest.mark.slow
def test_an_unskilled_signal_never_raises_an_alarm(make_log, tmp_path):
    log = make_log("paper-flow-sensor-covered", 12)
    code, report = diagnose_json(log)
    assert code == 1 and report["component"] == "flow_sensor"
    model = _unskilled_copy(tmp_path / "m", "flow")
    code, report = diagnose_json(log, "--model", str(model))
    assert code == 0 and report["verdict"] == "normal" and report["b"]["flow"] == 0
    assert report["not_judged"] == {"flow": "not judged (the model cannot predict it) "
                                            "(skill 0.05)"}
    assert report["model"]["skill"]["flow"] == 0.05
    pdf = tmp_path / "report.pdf"
    rendered = runner.invoke(app, ["diagnose", str(log), "--model", str(model), "--pdf",
                                   str(pdf), "--quiet"])
    assert rendered.exit_code == 0, rendered.output
    first = " ".join(pypdf.PdfReader(pdf).pages[0].extract_text().split())
    assert "NORMAL" in first
    assert "Not judged by the replay: flow: not judged (the model cannot" in first


def test_commands_reveal_what_an_unjudged_sensor_hides_without_blaming_a_thruster(
        make_log, tmp_path):
    """The covered flow sensor reads zero: the speed controller drives both thrusters
    harder than the measured motion needs. With the flow not judged, the commands still
    show the fault, and since both thrusters share the departure, neither is named."""
    log = make_log("paper-flow-sensor-covered", 12)
    model = _unskilled_copy(tmp_path / "m", "flow", relations=True)
    code, report = diagnose_json(log, "--model", str(model))
    check = report["commands_check"]
    assert code == 1 and report["verdict"] == "fault" and not any(report["b"].values())
    assert report["component"] is None and report["candidates"] == [] and check["named"] == []
    assert 115.0 < check["alarm_s"] < 150.0            # covered at 115 s
    assert max(check["explained"].values()) < 2.5 * min(check["explained"].values())
    assert any("no single actuator explains it" in note for note in report["notes"])


@pytest.mark.parametrize(("scenario", "component"), [
    ("paper-flow-sensor-covered", "flow_sensor"), ("mission-yaw-rate-sensor-dead",
                                                   "yaw_rate_sensor"),
    ("paper-normal", None)])
def test_a_finite_horizon_still_finds_and_names_a_failed_sensor(make_log, tmp_path, scenario,
                                                                component):
    """Re-started from the stuck reading every 8 s, the model departs from it again inside
    every stretch while the vehicle moves."""
    model = _shipped_copy(tmp_path / "h8", horizon_s=8.0)
    code, report = diagnose_json(make_log(scenario, 13), "--model", str(model))
    assert report["model"]["horizon_s"] == 8.0
    assert report["component"] == component and code == (0 if component is None else 1)


def _csv_dive(tmp_path: Path, scenario: str, seed: int, profile) -> Path:
    path = tmp_path / f"{scenario}-{seed}.csv"
    write_log(simulate(get_scenario(scenario, profile), profile, seed), profile, path, "csv")
    return path


def test_a_one_sample_spike_at_the_start_changes_no_verdict(tmp_path, profile):
    for scenario, verdict in (("paper-normal", "normal"), ("paper-flow-sensor-covered",
                                                           "fault")):
        clean = _csv_dive(tmp_path, scenario, 21, profile)
        _, before = diagnose_json(clean)
        table = pd.read_csv(clean)
        first = table["yaw_rate_rps"].first_valid_index()
        table.loc[first, "yaw_rate_rps"] = 3.84          # 220 deg/s for one sample
        spiked = tmp_path / f"spiked-{clean.name}"
        table.to_csv(spiked, index=False)
        _, after = diagnose_json(spiked)
        assert before["verdict"] == after["verdict"] == verdict
        assert after["component"] == before["component"]
        assert any("isolated spike(s) in yaw_rate" in note for note in after["notes"])
        peak = max(s["max_g"]["yaw_rate"] for s in after["segments"])
        assert peak < 1.2 * max(s["max_g"]["yaw_rate"] for s in before["segments"])


@pytest.mark.slow
def test_the_audit_table_names_the_signals_not_judged(make_log, tmp_path):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    (fleet / "dive.mcap").write_bytes(make_log("paper-flow-sensor-covered", 12, "mcap")
                                      .read_bytes())
    model = _unskilled_copy(tmp_path / "m", "flow")
    result = runner.invoke(app, ["audit", str(fleet), "--model", str(model), "--output",
                                 str(tmp_path / "audit"), "--jobs", "1"])
    assert result.exit_code == 0, result.output
    row = pd.read_csv(tmp_path / "audit" / "audit.csv").iloc[0]
    assert row["not_judged"] == "flow" and row["verdict"] == "normal"
    assert row["worst_g_signal"] == "yaw_rate"       # the worst g of a judged signal


@pytest.mark.slow
def test_too_little_held_out_data_judges_nothing(tmp_path):
    """A 30 s log leaves 6 s held out: about 60 samples cannot show skill, whatever the
    figure."""
    log = _noise_log(tmp_path / "short.csv", 5, seconds=30.0)
    model = tmp_path / "short-model"
    result = runner.invoke(app, ["train", str(log), "--output", str(model), "--keep-unskilled",
                                 "--iterations-scale", "0.01", "--hidden", "8",
                                 # too little to show any predictor's skill: the
                                 # least-squares one stands for them (no network trained)
                                 "--predictor", "linear"])
    assert result.exit_code == 1, result.output
    found = re.findall(r"NO: too little held-out data to measure it \((\d+) samples, needs "
                       r"200\)", result.stdout)
    assert len(found) == 2 and 50 <= int(found[0]) < 200, result.stdout
    code, report = diagnose_json(log, "--model", str(model))
    assert code == 0 and report["verdict"] == "undetermined"
    assert report["not_judged"]["flow"] == ("not judged (too little held-out data to measure "
                                            f"the model's skill: {found[0]} samples, needs 200)")


def test_rollouts_restart_every_horizon_from_a_median_start():
    from models.rollouts import plan_rollouts, start_states

    sensors = np.tile(np.arange(100.0)[:, None], (1, 2))
    sensors[40:45, 1] = np.nan                        # no gyro around the second re-start
    sensors[0, 0] = 1e3                               # an outlier in the first sample
    plan = plan_rollouts(sensors, [60], 20)
    # the re-start due at 42 waits until the gyro has a sample in its window (45 is in 43's)
    assert [(r.start, r.end) for r in plan] == [(2, 22), (22, 43), (43, 60), (62, 82),
                                                (82, 100)]
    assert {(r.stretch_begin, r.stretch_end) for r in plan} == {(0, 60), (60, 100)}
    states = start_states(sensors, plan)
    assert states[0].tolist() == [3.0, 2.0]           # medians of 0-4: the outlier moves
                                                      # flow's by one sample, no more
    assert states[2].tolist() == [43.0, 45.0]         # the gyro's one sample in 41-45
    assert states[3].tolist() == [62.0, 62.0]         # 60-64: never across the cut at 60
    assert plan_rollouts(sensors, [], None)[0].end == 100
