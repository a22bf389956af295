"""The change test: each log judged against its own beginning. Its statistic on residuals
with a known step, its thresholds set by calibrate from normal logs, and on simulated dives
whose fault begins mid-log: found after the onset and not before, no alarm on a normal
dive it was not calibrated on; the part that moves what changed is named."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers import zeroed_column
from typer.testing import CliRunner

from auvdiag_cli import api
from auvdiag_cli.cli import app
from auvdiag_cli.engine.change_check import REFERENCE_MIN_S, ChangeCheck, check_change
from auvdiag_cli.engine.change_check import WINDOW as WINDOW_Z
from auvdiag_cli.engine.change_statistics import SUM, change_statistics
from auvdiag_cli.engine.change_suspects import change_suspects
from auvdiag_cli.engine.diagnosis import check_model_fits
from auvdiag_cli.jobs.change_calibration import MIN_CHANGE_THRESHOLDS, MIN_FITTED_THRESHOLDS
from auvdiag_cli.reports.training import calibration_lines
from auvdiag_errors import ModelError

DT_S, WINDOW = 0.1, 10
runner = CliRunner()


def _limits(value: float) -> dict[str, dict[str, float]]:
    return {WINDOW_Z: {"speed": value, "yaw": value}, SUM: {"speed": 3 * value, "yaw": 3 * value}}


def _noise(seconds: float, signals: int = 2, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, 1.0, (round(seconds / DT_S), signals))


def _checked(residual: np.ndarray, stride: int | None = 1) -> ChangeCheck:
    """The test on two signals, "speed" and "yaw", each with the same thresholds."""
    time_s = np.arange(residual.shape[0]) * DT_S
    return check_change(residual, ["speed", "yaw"], _limits(7.0), time_s, WINDOW, DT_S,
                        stride=stride)


def test_the_statistic_waits_for_its_reference_and_rises_at_a_step():
    residual = _noise(120.0)
    residual[800:, 1] += 3.0                         # signal 1 shifts at 80 s
    z = change_statistics(residual, WINDOW, round(REFERENCE_MIN_S / DT_S))[WINDOW_Z]
    assert np.isnan(z[:round(REFERENCE_MIN_S / DT_S), :]).all()
    assert np.nanmax(z[:800]) < 6.0                  # noise alone
    assert np.nanmax(z[800:810, 1]) > 8.0            # the shift, within a window
    assert np.nanmax(z[800:, 0]) < 6.0               # the other signal is untouched


def test_a_shift_no_single_window_shows_builds_up_window_after_window():
    residual = _noise(150.0, seed=4)
    residual[800:, 0] += 0.6              # about two spreads of a window mean, for good
    statistics = change_statistics(residual, WINDOW, round(REFERENCE_MIN_S / DT_S))
    sums, z = statistics[SUM][:, 0], statistics[WINDOW_Z][:, 0]
    assert np.nanmax(sums[:800]) < 5.0 and np.nanmax(z[800:]) < 4.5   # no window stands out
    assert sums[829] < sums[859] < sums[899] and sums[899] > 5.0


def test_the_check_dates_the_change_within_a_window_and_names_the_signal():
    residual = _noise(120.0, seed=1)
    residual[800:, 0] -= 3.0
    check = _checked(residual)
    # The first window whose earlier windows hold the reference: judged from its end.
    assert check.judged and check.judged_from_s == pytest.approx(
        REFERENCE_MIN_S + (WINDOW - 1) * DT_S, abs=0.05)
    assert 80.0 <= check.alarm_s <= 81.0
    assert check.onset_s == pytest.approx(80.0, abs=check.onset_error_s)
    assert list(check.flagged) == ["speed"] and check.ways == {"speed": "below"}
    assert "changed against the log's own beginning" in check.describe()
    assert "(below the prediction)" in check.describe()


@pytest.mark.parametrize("drift_from_s", [20.0, 25.0])
def test_a_change_begun_within_the_reference_may_be_dated_back_to_the_log_start(drift_from_s):
    """A drift that began before the test could judge (in the log's first 30 s, its
    reference; an engine losing thrust): seen once judging begins, its stated onset
    reaches back to the log's start, where it may lie, and the words say so; a drift that
    begins after the reference is dated within it as before."""
    def drifting(start_s: float) -> ChangeCheck:
        residual = _noise(90.0)
        time_s = np.arange(residual.shape[0]) * DT_S
        residual[:, 1] += np.where(time_s >= start_s, 0.3 * (time_s - start_s), 0.0)
        return _checked(residual)

    check = drifting(drift_from_s)
    assert check.alarm_s is not None and check.since_judged
    assert check.onset_s - check.onset_error_s <= 0.0 and drift_from_s <= check.alarm_s
    assert "or earlier (its sum ran from the first step judged" in check.describe()
    later = drifting(60.0)
    assert later.alarm_s is not None and not later.since_judged
    assert 30.0 < later.onset_s - later.onset_error_s <= 60.0


def test_a_window_judged_every_step_sees_a_change_sooner_than_windows_side_by_side():
    residual = _noise(120.0, seed=1)
    residual[803:, 0] -= 3.0                  # 0.3 s into a window of the row side by side
    every, side = _checked(residual), _checked(residual, stride=None)
    assert side.alarm_s is not None and every.alarm_s is not None
    assert (side.alarm_s * 10) % 10 == pytest.approx(9.0)       # only at a row's window ends
    assert 80.3 < every.alarm_s < side.alarm_s and every.alarm_s <= 81.1
    for check in (every, side):
        assert check.onset_s == pytest.approx(80.3, abs=check.onset_error_s)
        assert list(check.flagged) == ["speed"]
    # A window judged every step is measured against every earlier window that does not
    # overlap it, of whichever phase: the window means ending up to a window before it.
    reference = round(REFERENCE_MIN_S / DT_S)
    z = change_statistics(residual, WINDOW, reference)[WINDOW_Z][:, 1]
    means = np.convolve(residual[:, 1], np.ones(WINDOW) / WINDOW, mode="valid")  # end i+9
    for end in (reference + WINDOW - 1, 555, 1000):
        earlier = means[:end - WINDOW - (WINDOW - 1) + 1]
        expected = (means[end - (WINDOW - 1)] - earlier.mean()) / earlier.std()
        assert z[end] == pytest.approx(abs(expected), rel=1e-9)
    assert np.isnan(z[reference + WINDOW - 2])          # one step short of its reference
    with pytest.raises(ValueError, match="does not divide"):
        change_statistics(residual, WINDOW, reference, stride=3)


def test_judged_every_step_a_transient_reads_the_same_wherever_the_recording_started():
    # A normal transient 1.2 s long at 60 s. Windows side by side see it whole or split in
    # two depending on where the recording started, so a normal log's verdict could hang on
    # that; judged every step, its window is found wherever the log begins.
    residual = np.random.default_rng(2).normal(0.0, 1.0, (1200, 1))
    residual[600:612, 0] += 2.0
    reference = round(REFERENCE_MIN_S / DT_S)

    def largest(stride: int | None) -> np.ndarray:
        return np.array([np.nanmax(change_statistics(residual[late:], WINDOW, reference,
                                                     stride=stride)[WINDOW_Z])
                         for late in range(WINDOW)])

    every, side = largest(1), largest(None)
    assert every.max() - every.min() < 0.1
    assert side.max() - side.min() > 2.0 and every.min() >= side.max() - 0.3


def test_noise_lingering_in_the_sum_does_not_date_an_abrupt_change_early():
    residual = _noise(120.0, seed=1)
    residual[700:, 0] += 0.4          # a slight drift from 70 s keeps the sum above 0 ...
    residual[803:, 0] += 3.0          # ... when the change comes at 80.3 s
    sums = change_statistics(residual, WINDOW, round(REFERENCE_MIN_S / DT_S))[SUM][:, 0]
    assert (sums[760:803] > 0).all()
    check = _checked(residual)
    assert check.alarm_s is not None and 80.3 < check.alarm_s <= 81.2
    assert check.onset_s == pytest.approx(80.3, abs=0.3) and check.onset_error_s <= 1.0


def test_what_crosses_within_a_window_of_the_alarm_is_flagged_with_it():
    # A failure moves both signals; the second 0.6 s after the first. At the first step over
    # a threshold only the first has crossed; the window after it counts the second, while
    # the first still dates the change.
    residual = _noise(120.0, seed=1)
    residual[800:, 0] += 3.0
    residual[806:, 1] += 3.0
    check = _checked(residual)
    assert check.alarm_s is not None and check.alarm_s <= 80.9
    assert set(check.flagged) == {"speed", "yaw"}
    assert check.ways == {"speed": "above", "yaw": "above"}
    assert check.onset_s == pytest.approx(80.0, abs=0.2)


def test_a_log_shorter_than_its_reference_is_not_judged():
    residual = _noise(REFERENCE_MIN_S - 5.0)
    check = check_change(residual, ["a", "b"], {WINDOW_Z: {"a": 5.0, "b": 5.0}},
                         np.arange(residual.shape[0]) * DT_S, WINDOW, DT_S)
    assert not check.judged and check.alarm_s is None and "too short" in check.describe()


def test_the_part_moving_most_of_what_changed_comes_first():
    profile = api.load_profile("arduplane_carbonz")
    assert change_suspects({"yaw_rate": 2.0}, profile)[:2] == ["rudder", "gyro"]
    assert change_suspects({"pitch": 1.5, "pitch_rate": 1.2}, profile) == ["elevator"]
    # A part moving several signals far past their thresholds gathers their weight ...
    assert change_suspects({"climb": 1.6, "accel_x": 1.5, "roll": 1.8}, profile)[0] == "engine"
    # ... but one that moved a signal far outweighs one that nudged several.
    assert change_suspects({"yaw_rate": 1.9, "climb": 1.75, "roll": 1.27, "roll_rate": 1.07},
                           profile)[:3] == ["rudder", "engine", "ailerons"]


def test_what_a_signal_carried_from_the_onset_outweighs_what_crossed_at_the_alarm():
    # Signal 0 drifts from 80 s, about two spreads of a window mean, for good, and stays
    # under its thresholds; signal 1 jumps at 89 s and crosses at once (the vehicle's
    # answer): the alarm is signal 1's, but over the run up to it signal 0 carried more
    # above its usual level.
    residual = _noise(150.0, seed=4)
    residual[800:, 0] += 0.6
    residual[890:, 1] += 4.0
    check = _checked(residual)
    # Judged every step: the window ending 0.6 s after the jump holds six steps of it.
    assert check.alarm_s == pytest.approx(89.5) and list(check.flagged) == ["yaw"]
    assert check.evidence["speed"] > check.evidence["yaw"] > 0.0
    # The way each moved is kept for what it carried, not only for what crossed.
    assert check.ways == {"speed": "above", "yaw": "above"}
    # On the aircraft: the engine's signals carried the change from the onset, the roll
    # rate crossed at the alarm; without what was carried, the ailerons come first.
    profile = api.load_profile("arduplane_carbonz")
    flagged = {"roll_rate": 1.3}
    carried = {"accel_x": 0.6, "climb": 0.4, "ground_speed": 0.1, "roll_rate": 0.3}
    assert change_suspects(flagged, profile)[0] == "ailerons"
    assert change_suspects(flagged, profile, carried)[0] == "engine"


def test_a_signal_moved_the_way_a_parts_weakening_moves_it_counts_for_that_part():
    # An engine failure of ALFA (2018-07-18-16-37-39_2) as a model of three normal flights
    # of another day saw it: the pitch crossed, below the prediction (the autopilot lowering
    # the nose), the engine's signature carried a quarter of its threshold. The elevator
    # moves the pitch either way; the engine's declared weakening moves it below, so a
    # pitch below counts for the engine as well.
    profile = api.load_profile("arduplane_carbonz")
    flagged = {"pitch": 1.18}
    carried = {"roll": 0.087, "pitch": 0.331, "roll_rate": 0.316, "pitch_rate": 0.03,
               "yaw_rate": 0.14, "accel_x": 0.071, "engine weakened": 0.253}
    assert change_suspects(flagged, profile, carried, {"pitch": "below"})[0] == "engine"
    # Above the prediction, the engine's weakening does not explain it.
    assert change_suspects(flagged, profile, carried, {"pitch": "above"})[0] == "rudder"
    assert change_suspects(flagged, profile, carried)[0] == "rudder"


def test_a_sensor_is_suspected_only_where_every_change_is_its_own():
    profile = api.load_profile("arduplane_carbonz")
    # yaw and roll rate are the gyro's, the climb the GPS's: no one sensor reads them all.
    spread = change_suspects({"yaw_rate": 1.5, "climb": 1.12, "roll_rate": 1.08}, profile)
    assert spread == ["rudder", "engine", "ailerons"]
    assert change_suspects({"pitch_rate": 1.5, "yaw_rate": 1.4}, profile)[0] == "gyro"
    # The rudder rolls the aircraft too: a stuck rudder's yaw rate and the roll rate it
    # brings are its own, not a gyro fault on two axes (as a model of one day's ALFA flights
    # saw a rudder failure: carried yaw rate 0.27, roll rate 0.01).
    rudder = change_suspects({"yaw_rate": 2.1, "roll_rate": 1.0}, profile,
                             {"yaw_rate": 0.27, "roll_rate": 0.01})
    assert rudder[:2] == ["rudder", "gyro"]


@pytest.fixture(scope="module")
def calibrated(make_log, tmp_path_factory):
    """The built-in model calibrated on three normal dives: the change test's thresholds."""
    model = api.load_model(None)
    normal = [make_log("paper-normal", seed) for seed in (3, 4, 5)]
    result = api.calibrate(normal, api.load_profile(None), model)
    return model, result


def test_calibrate_sets_a_change_threshold_per_judged_signal(calibrated):
    model, result = calibrated
    assert model.card.change_stride == 1        # a window judged every step
    # A model calibrated before judged windows side by side, as its thresholds were set.
    entry = json.loads(model.card.document_text)["change_test"]
    del entry["stride_steps"]
    assert model.with_entries(change_test=entry).card.change_stride is None
    # A stride that does not divide the window is refused with one line naming the log.
    odd = model.with_entries(change_test={**entry, "stride_steps": 7})
    log = Path("dive.bag")
    with pytest.raises(ModelError, match=r"dive\.bag: .*stride_steps 7 does not divide"):
        check_model_fits(odd, api.load_profile(None), log)
    assert set(result.change) == {WINDOW_Z, SUM}
    for statistic, values in result.change.items():
        assert set(values) == {"flow", "yaw_rate"}
        for name, (largest, threshold) in values.items():
            assert threshold == pytest.approx(
                max(1.5 * largest, MIN_CHANGE_THRESHOLDS[statistic]), rel=1e-3)
            assert model.card.change_thresholds[statistic][name] == pytest.approx(threshold)
    assert any(line.startswith("  change test") for line in calibration_lines(result))


def test_a_normal_dive_it_was_not_calibrated_on_raises_no_change(calibrated, make_log):
    model, _ = calibrated
    diagnosis = api.diagnose(make_log("paper-normal", 9), api.load_profile(None), model)
    check = diagnosis.change_check
    assert check is not None and check.judged and check.alarm_s is None
    assert diagnosis.verdict == "normal"
    # It says from when it judged: what came before is its reference, where it sees nothing.
    assert check.judged_from_s is not None and check.judged_from_s >= REFERENCE_MIN_S
    assert check.describe().startswith(f"no change after {check.judged_from_s:.1f} s against "
                                       "the log's own beginning before it")


def test_a_thruster_weakening_mid_log_is_found_first_by_the_change_test(calibrated,
                                                                        make_log):
    """Thruster 0 gives half its power from 60 s: the replay's thresholds alone find it at
    74 s; the log against its own beginning, seconds sooner. The hypotheses name it."""
    model, _ = calibrated
    log = make_log("mission-thruster-0-weak", 11)
    diagnosis = api.diagnose(log, api.load_profile(None), model)
    check = diagnosis.change_check
    assert check is not None and check.alarm_s is not None
    without = api.diagnose(log, api.load_profile(None), model.with_entries(change_test={}))
    assert without.change_check is None and without.detected_at_s > 70.0
    assert 60.0 < check.alarm_s < without.detected_at_s - 4.0
    assert diagnosis.detected_at_s == check.alarm_s
    assert (diagnosis.verdict, diagnosis.component) == ("fault", "thruster_0")
    assert check.onset_s - check.onset_error_s <= 60.0 <= check.onset_s + check.onset_error_s
    assert any(note.startswith("found by the change test") for note in diagnosis.notes)


def test_the_report_draws_what_the_change_test_judged(calibrated, make_log, tmp_path):
    """The change test found it: the PDF draws each judged signal over its threshold, not
    judged while its reference fills, above it from the alarm; `auvdiag report` draws it
    again from the saved time histories."""
    import pypdf

    from auvdiag_cli.reports.series import load_series
    model, _ = calibrated
    diagnosis = api.diagnose(make_log("mission-thruster-0-weak", 11), api.load_profile(None),
                             model)
    check = diagnosis.change_check
    assert check is not None and check.alarm_s is not None and check.judged_from_s is not None
    json_path, pdf, mcap = tmp_path / "d.json", tmp_path / "d.pdf", tmp_path / "d.mcap"
    api.write_reports(diagnosis, json=json_path, pdf=pdf, mcap=mcap)
    series = load_series(tmp_path / "d.series.npz")
    names = [str(n) for n in series["change_names"]]
    assert names == list(check.ratio_names) and set(names) == {"flow", "yaw_rate"}
    ratio, time_s = series["change_ratio"], series["time_s"]
    assert np.isnan(ratio[time_s < check.judged_from_s - 0.5]).all()
    at = int(np.searchsorted(time_s, check.alarm_s))
    assert np.nanmax(ratio[at]) > 1.0 and (np.nan_to_num(ratio[:at]) <= 1.0).all()
    pages = [page.extract_text() for page in pypdf.PdfReader(pdf).pages]
    drawn = [text for text in pages if "Against the log's own beginning: each signal's" in text]
    assert len(drawn) == 1 and all(name in drawn[0] for name in names)
    # No Diagnosis Motion Sequences in this log: no page says they are shaded.
    assert not any("shaded: Diagnosis Motion Sequences" in text for text in pages)
    again = tmp_path / "again.pdf"
    result = runner.invoke(app, ["report", str(json_path), "--output", str(again)])
    assert result.exit_code == 0, result.output
    assert [p.extract_text() for p in pypdf.PdfReader(again).pages][1:] == pages[1:]
    # The MCAP carries it too, a message each step, for a plot beside the log.
    from mcap.reader import make_reader
    with mcap.open("rb") as stream:
        bodies = [json.loads(m.data) for _, channel, m in make_reader(stream).iter_messages()
                  if channel.topic == "/auvdiag/change"]
    assert len(bodies) == time_s.size and set(bodies[at]) == set(names)
    assert max(v for v in bodies[at].values() if v is not None) > 1.0
    assert bodies[0] == {name: None for name in names}


def test_a_signal_judged_only_against_its_own_log_is_left_to_the_change_test(calibrated,
                                                                            make_log,
                                                                            tmp_path):
    """A sensor the profile has judged only against the log's own beginning (a ground speed
    with the day's wind) raises no replay bit and takes no replay threshold, but the change
    test judges it and the coverage counts it; a sensor a log never fed is set aside by
    every judge, the change test too."""

    from auvdiag_cli.engine.judging import replay_judged

    model, _ = calibrated
    base = api.load_profile(None)
    profile = replace(base, sensors=tuple(
        replace(s, own_log_only="a flow that depends on the day's current")
        if s.name == "flow" else s for s in base.sensors))
    assert replay_judged(model, profile) == ["yaw_rate"]
    diagnosis = api.diagnose(make_log("mission-thruster-0-weak", 11), profile, model)
    assert diagnosis.not_judged["flow"].startswith("judged only against the log's own")
    check = diagnosis.change_check
    assert check is not None and all("flow" in limits for limits in check.thresholds.values())
    assert "flow" in diagnosis.coverage.signals_judged and diagnosis.set_aside == ()
    assert (diagnosis.histories.b_series[:, 0] == 0).all()
    # A channel never fed (the flow's cells all 0): set aside, the change test leaves it out.
    zeroed = zeroed_column(make_log("paper-normal", 9, "csv"), "flow_mps",
                           tmp_path / "no_flow.csv")
    flat = api.diagnose(zeroed, base, model)
    assert flat.set_aside == ("flow",) and flat.change_check is not None
    assert all(list(limits) == ["yaw_rate"] for limits in flat.change_check.thresholds.values())
    assert "flow" not in flat.coverage.signals_judged


def test_a_log_whose_every_signal_is_left_to_the_change_test_is_still_judged(calibrated,
                                                                              make_log):
    """Every sensor judged only against the log's own beginning: the replay judges nothing,
    but the change test does, and its alarm makes the verdict (it was "undetermined": "no
    signal is judged")."""

    from auvdiag_cli.engine.coverage import Coverage
    from auvdiag_cli.engine.judging import Judging, nothing_judged, replay_judged
    from auvdiag_cli.reports.pdf.facts import assumption_remarks, summary_facts
    from auvdiag_cli.reports.report_build import build_report
    from auvdiag_cli.reports.text import summary_lines

    model, _ = calibrated
    base = api.load_profile(None)
    profile = replace(base, sensors=tuple(replace(s, own_log_only="judged against itself")
                                          for s in base.sensors))
    assert replay_judged(model, profile) == []
    diagnosis = api.diagnose(make_log("mission-thruster-0-weak", 11), profile, model)
    check = diagnosis.change_check
    assert check is not None and check.alarm_s is not None
    assert diagnosis.verdict == "fault" and diagnosis.detected_at_s == check.alarm_s
    assert not any("no signal is judged" in note for note in diagnosis.notes)
    # The report says the reason they share once, and that the replay judges none of them.
    lines = summary_lines(build_report(diagnosis))
    said = [line for line in lines if line.endswith("(judged against itself)")]
    assert said == ["  " + ", ".join(profile.sensor_names) + ": judged only against the "
                    "log's own beginning (judged against itself)"]
    assert any(line.endswith("max g / threshold: none judged by the replay") for line in lines)
    report = build_report(diagnosis)
    (left_out,) = [value for label, value in summary_facts(report)
                   if label == "Not judged by the replay"]
    assert left_out.count("judged only against the log's own beginning") == 1
    series = {"time_s": diagnosis.histories.time_s, "sensor_names": profile.sensor_names,
              "g_percent": np.zeros((len(diagnosis.histories.time_s), len(profile.sensors))),
              "thresholds": np.ones((len(diagnosis.histories.time_s), len(profile.sensors)))}
    assert assumption_remarks(report, series)[0][1].startswith("the replay judges no signal")
    normal = api.diagnose(make_log("paper-normal", 12), profile, model)
    assert normal.verdict == "normal" and normal.change_check is not None
    # Its NORMAL says from when it judged: what came before is the change test's reference.
    coverage = normal.coverage
    since = normal.change_check.judged_from_s
    assert since is not None and coverage.judged_from_s == since and not coverage.complete
    assert f"2 of 2 signals judged from {since:.1f} s and" in coverage.counts()
    assert Coverage.from_dict(coverage.to_dict()) == coverage
    assert api.diagnose(make_log("paper-normal", 12), base, model).coverage.judged_from_s is None
    # Where the change test cannot judge either, the note says why, not "cannot predict".
    n = len(profile.sensors)
    assert nothing_judged(Judging.of(model, profile), None) == (
        f"no signal is judged: {n} of {n} are judged only against the log's own beginning, "
        "by the change test, and it is not calibrated (run `auvdiag calibrate` on normal logs)")
    assert nothing_judged(Judging.of(model, base), None).endswith("cannot predict any of them")
    # Calibrated on logs that let it judge too briefly: it says that, not "not calibrated".
    brief = model.with_entries(change_test={"thresholds": {}, "judged_too_briefly_s": {
        "flow": 12.5, "yaw_rate": 20.0}})
    assert brief.card.change_too_brief == {"flow": 12.5, "yaw_rate": 20.0}
    assert nothing_judged(Judging.of(brief, profile), None).endswith(
        "by the change test, and calibrate's normal logs let it judge them too briefly to set "
        "its thresholds (20.0 s in all at most; calibrate on more or longer normal logs)")


def test_the_failures_effect_is_the_gap_to_the_healthy_model_from_the_onset():
    from types import SimpleNamespace

    from auvdiag_cli.engine.failure_effect import failure_effect, healthy_from_onset

    time_s = np.arange(1000) * DT_S
    measured = np.zeros((1000, 2))
    measured[600:, 1] = 0.2                               # yaw rate off from 60 s
    modelled = np.zeros((1000, 2))
    # the replay that re-starts from the measured state every horizon catches up; the
    # healthy vehicle started at the onset does not
    modelled[600:, 1] = 0.1
    healthy = np.zeros((1000, 2))
    seen = SimpleNamespace(
        histories=SimpleNamespace(time_s=time_s, sensor_names=("roll", "yaw_rate"),
                                  matching=SimpleNamespace(measured=measured,
                                                           modelled=modelled)),
        sensor_units={"yaw_rate": "rad/s"})
    check = check_change(measured - healthy + _noise(100.0, seed=2) * 0.01,
                         ["roll", "yaw_rate"], {WINDOW_Z: {"roll": 8.0, "yaw_rate": 8.0}},
                         time_s, WINDOW, DT_S)
    assert list(check.flagged) == ["yaw_rate"]
    assert check.onset_s is not None and abs(check.onset_s - 60.0) <= check.onset_error_s
    effect = failure_effect(seen, check, healthy, horizon_steps=40)
    assert effect.startswith("from the onset, the vehicle departs from what the model of "
                             "the healthy vehicle says it would have done by yaw_rate ")
    gap = float(effect.split("yaw_rate ")[1].split()[0])
    assert 0.18 <= gap <= 0.2 and "rad/s rms (before: 0)" in effect
    start = int(np.searchsorted(time_s, check.onset_s))
    assert effect.endswith(f"{time_s[start + 39] - time_s[start]:.1f} s after the onset the "
                           "healthy vehicle would have read yaw_rate 0 where it read 0.2 rad/s")
    assert failure_effect(seen, check, healthy, horizon_steps=None).endswith(
        f"{time_s[-1] - check.onset_s:.1f} s after the onset the healthy vehicle would have "
        "read yaw_rate 0 where it read 0.2 rad/s")
    # The log's last reading left out (a spike): the values are said where it has one.
    measured[-1, 1] = np.nan
    effect = failure_effect(seen, check, healthy, horizon_steps=None)
    assert "nan" not in effect and effect.endswith(
        f"{time_s[-2] - check.onset_s:.1f} s after the onset the healthy vehicle would have "
        "read yaw_rate 0 where it read 0.2 rad/s")
    # A signal the model cannot predict: its gap would be the model's own error, not the
    # failure's effect, and where it "would have read" a guess.
    assert failure_effect(seen, check, healthy, None, {"yaw_rate": "-0.51"}) == (
        "the model of the healthy vehicle cannot say what yaw_rate would have done (its "
        "skill on normal logs left out of its training: yaw_rate -0.51)")
    assert failure_effect(seen, check, healthy, None, {"roll": "0.10"}) == effect
    # What the report draws: the first replay from the onset, in what the model predicts.
    drawn = healthy_from_onset(seen, check, healthy, 40, {"roll": "0.10"})
    assert drawn is not None and np.isnan(drawn[:, 0]).all()
    replayed = np.flatnonzero(np.isfinite(drawn[:, 1]))
    assert (replayed[0], replayed[-1]) == (start, start + 39)
    assert healthy_from_onset(seen, replace(check, onset_s=None), healthy, 40) is None


def test_change_judges_no_log_is_long_enough_for_take_no_share_of_the_budget():
    from auvdiag_cli.jobs.budget import change_judges

    short = {WINDOW_Z: {"depth": float("nan")}, SUM: {"depth": float("nan")}}
    long = {WINDOW_Z: {"depth": 3.0}, SUM: {"depth": float("nan")}}
    assert change_judges([short, short], ["depth"]) == []
    assert [(j.name, j.mode) for j in change_judges([short, long], ["depth"])] == [
        ("depth", WINDOW_Z)]


def test_one_normal_log_that_alone_sets_a_change_threshold_is_named():
    from auvdiag_cli.jobs.change_calibration import ChangeEvidence, dominated_by_one_log

    peaks = [{WINDOW_Z: {"climb": 3.0}, SUM: {"climb": 4.0}},
             {WINDOW_Z: {"climb": 3.5}, SUM: {"climb": 30.0}},
             {WINDOW_Z: {"climb": float("nan")}, SUM: {"climb": 5.0}}]
    warnings = dominated_by_one_log(ChangeEvidence(["climb"], peaks), ["a", "odd", "b"])
    assert warnings == [
        "odd alone sets the change test's thresholds of climb (sum: 30.0, 6.0x the next "
        "log's): check that log for a failure or a disturbance; if it was not normal, "
        "calibrate without it"]


def test_one_log_far_beyond_every_other_is_left_out_of_the_thresholds_and_named():
    from auvdiag_cli.jobs.change_calibration import (
        ChangeEvidence,
        change_thresholds,
        dominated_by_one_log,
        without_outliers,
    )

    sums = [4.0, 5.1, 3.2, 4.4, 26.9, 3.8]      # one flight that lost height at full throttle
    peaks = [{WINDOW_Z: {"climb": 3.0 + i / 10}, SUM: {"climb": s}} for i, s in enumerate(sums)]
    names = ["a", "b", "c", "d", "odd", "e"]
    evidence = without_outliers(ChangeEvidence(["climb"], peaks))
    assert [(o.log, o.statistic, o.value, o.following) for o in evidence.outliers] == [
        (4, SUM, 26.9, 5.1)]
    thresholds = change_thresholds(evidence, 2.0, None)
    assert thresholds[SUM]["climb"] == (5.1, 10.2)              # from the other five
    assert thresholds[WINDOW_Z]["climb"] == (3.5, 7.0)          # its window kept: not an outlier
    assert dominated_by_one_log(evidence, names) == [
        "odd left out of the change test's thresholds of climb (sum: 26.9, 5.3x the next "
        "log's): a log that departs from its own beginning so far beyond every other is taken "
        "for one that was not normal; check it for a failure or a disturbance"]
    # Under the statistic's floor no value sets a threshold: none left out, none named.
    quiet = [{SUM: {"climb": v}} for v in (0.1, 0.3, 0.05, 0.2, 0.7)]
    calm = without_outliers(ChangeEvidence(["climb"], quiet))
    assert calm.outliers == () and dominated_by_one_log(calm, names[:5]) == []
    # With fewer logs the next log's value says too little: kept, and only named.
    few = without_outliers(ChangeEvidence(["climb"], peaks[2:5]))
    assert few.outliers == () and change_thresholds(few, 2.0, None)[SUM]["climb"][0] == 26.9


def test_a_law_fitted_to_enough_logs_sets_the_threshold_below_the_margin_rules_floor():
    """Twelve normal logs whose sums peak at 2-4: the law fitted to them (its share checked
    on each log left out) sets the sum's threshold, below the floor that guards the margin
    rule; four logs fit no law, and the floor holds."""
    from auvdiag_cli.jobs.budget import FalseAlarmBudget, budget_thresholds, change_judges
    from auvdiag_cli.jobs.change_calibration import ChangeEvidence, change_thresholds

    peaks = [{SUM: {"climb": value}, WINDOW_Z: {"climb": value + 1.0}}
             for value in np.random.default_rng(3).uniform(2.0, 4.0, 12)]
    budget = FalseAlarmBudget.parse("0.05")

    def thresholds(logs: list[dict[str, dict[str, float]]]) -> dict[str, float]:
        fitted = budget_thresholds(change_judges(logs, ["climb"]), 0, budget,
                                   [0.05] * len(logs))
        result = change_thresholds(ChangeEvidence(["climb"], logs), 1.5, fitted)
        return {statistic: values["climb"][1] for statistic, values in result.items()}

    many = thresholds(peaks)
    largest = max(p[SUM]["climb"] for p in peaks)
    assert largest < many[SUM] < MIN_CHANGE_THRESHOLDS[SUM]
    few = thresholds(peaks[:4])
    assert few[SUM] == MIN_CHANGE_THRESHOLDS[SUM]       # 1.5 x a sum of 2-4 is below it
    largest_window = max(p[WINDOW_Z]["climb"] for p in peaks[:4])
    assert few[WINDOW_Z] == pytest.approx(
        max(1.5 * largest_window, MIN_CHANGE_THRESHOLDS[WINDOW_Z]), abs=1e-3)
    # Logs that all stayed quiet fit a law of no spread: its threshold would be 0.
    quiet = thresholds([{SUM: {"climb": 0.0}, WINDOW_Z: {"climb": 2.0}} for _ in range(8)])
    assert quiet[SUM] == MIN_FITTED_THRESHOLDS[SUM]


def _bursts_above(seed: int, seconds: float = 150.0) -> np.ndarray:
    """A normal log's residual whose excursions go above the prediction: noise, with a
    burst of +2.5 for 2 s every 30 s (a throttle-up's overshoot, say)."""
    residual = _noise(seconds, signals=1, seed=seed)
    for start in range(450, residual.shape[0] - 20, 300):
        residual[start:start + 20, 0] += 2.5
    return residual


def test_each_way_is_scaled_by_how_far_normal_logs_go_that_way():
    from auvdiag_cli.jobs.change_calibration import MIN_LOGS_FOR_WAYS, change_peaks, way_scales

    reference = round(REFERENCE_MIN_S / DT_S)
    normal = [_bursts_above(seed) for seed in range(MIN_LOGS_FOR_WAYS + 1)]
    peaks = [change_peaks(r, ["speed"], WINDOW, DT_S)[0] for r in normal]
    scales = way_scales(peaks, ["speed"])
    for statistic in (WINDOW_Z, SUM):
        above, below = scales[statistic]["speed"]
        assert above > 1.0 > below and above * below == pytest.approx(1.0, abs=1e-3)
    assert way_scales(peaks[:MIN_LOGS_FOR_WAYS - 1], ["speed"]) == {}

    def thresholds(with_scales: bool) -> dict[str, dict[str, float]]:
        """1.2 x the largest of each statistic on the normal logs, as judged."""
        largest: dict[str, float] = {}
        for residual in normal:
            for statistic, values in change_statistics(
                    residual, WINDOW, reference, scales=scales if with_scales else None,
                    names=["speed"]).items():
                largest[statistic] = max(largest.get(statistic, 0.0),
                                         float(np.nanmax(values)))
        return {statistic: {"speed": 1.2 * value} for statistic, value in largest.items()}

    # A drop that lasts: judged either way, the thresholds the bursts above set hide it for
    # long; each way scaled by its own, it is found soon after it began.
    drop = _noise(150.0, signals=1, seed=9)
    drop[900:, 0] -= 1.0
    time_s = np.arange(drop.shape[0]) * DT_S
    alike = check_change(drop, ["speed"], thresholds(False), time_s, WINDOW, DT_S)
    apart = check_change(drop, ["speed"], thresholds(True), time_s, WINDOW, DT_S,
                         scales=scales)
    assert apart.alarm_s is not None and 90.0 <= apart.alarm_s <= 95.0
    assert alike.judged and (alike.alarm_s is None or alike.alarm_s > apart.alarm_s + 10.0)
    # A normal log of the same kind passes both.
    quiet = _bursts_above(11)
    assert check_change(quiet, ["speed"], thresholds(True), time_s, WINDOW, DT_S,
                        scales=scales).alarm_s is None


def test_a_signal_left_to_the_change_test_that_it_cannot_predict_says_why_it_is_not_judged(
        calibrated, make_log):
    """Where the predictor a moment ahead barely beats "no change" on a signal the profile
    judges only against the log's own beginning, nothing judges it: the report says so and
    why, not that the change test judges it."""

    from auvdiag_cli.audit.record import AuditRecord
    from auvdiag_cli.audit.table import table_row
    from auvdiag_cli.engine.change_columns import MIN_AHEAD_SKILL
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.reports.report_build import build_report
    from auvdiag_cli.reports.text import summary_lines
    from models.ahead import AheadLog, fit_ahead

    model, _ = calibrated
    base = api.load_profile(None)
    profile = replace(base, sensors=tuple(replace(s, own_log_only="judged against itself")
                                          for s in base.sensors))
    frames = [ingest(make_log("paper-normal", seed), base).frame for seed in (21, 22, 23)]
    ahead = fit_ahead([AheadLog(f.commands, f.sensors) for f in frames], base.sensor_names,
                      base.dt_s)
    assert ahead is not None and ahead.skill["flow"] >= MIN_AHEAD_SKILL
    unskilled = model.with_entries(ahead_predictor={
        **ahead.to_json(), "heldout_skill": {**ahead.skill, "flow": 0.04}})
    diagnosis = api.diagnose(make_log("paper-normal", 12), profile, unskilled)
    assert diagnosis.change_check is not None and diagnosis.change_check.judged
    assert diagnosis.coverage.signals_not_judged == ("flow",)
    assert diagnosis.not_judged["flow"] == (
        "not judged (its predictor a moment ahead barely beats no change: skill 0.04, judged "
        "from 0.1; the profile judges it only against the log's own beginning)")
    assert diagnosis.not_judged["yaw_rate"] == ("judged only against the log's own "
                                                "beginning (judged against itself)")
    report = build_report(diagnosis)
    assert "  flow: " + diagnosis.not_judged["flow"] in summary_lines(report)
    # The audit's table says what nothing judged, not what the replay left to the test.
    row = table_row(AuditRecord.from_report(report.to_json()))
    assert (row["not_judged"], row["signals_judged"]) == ("flow", "1/2")
    # Where it does judge every such signal, each keeps the profile's reason.
    judged = api.diagnose(make_log("paper-normal", 12), profile, model.with_entries(
        ahead_predictor=ahead.to_json()))
    assert judged.coverage.signals_not_judged == ()
    assert set(judged.not_judged.values()) == {"judged only against the log's own beginning "
                                               "(judged against itself)"}


def test_a_signal_the_normal_logs_judge_too_briefly_gets_no_threshold():
    """Seconds of a statistic say nothing of how far it goes when nothing fails: a signal
    the normal logs let the test judge for less than MIN_JUDGED_S all together gets no
    threshold and no share of the budget; the logs' seconds add up; a log trained on before
    the model recorded its seconds leaves the total unknown, and the signal kept."""
    from auvdiag_cli.engine.change_check import MIN_JUDGED_S
    from auvdiag_cli.jobs.budget import change_judges
    from auvdiag_cli.jobs.change_calibration import ChangeEvidence, change_thresholds, enough_judged

    def peaks(value: float) -> dict[str, dict[str, float]]:
        return {WINDOW_Z: {"roll": value, "loop": value}, SUM: {"roll": value, "loop": value}}

    evidence = ChangeEvidence(["roll", "loop"], [peaks(2.0), peaks(3.0)])
    brief = MIN_JUDGED_S / 3
    seconds = [{"roll": 2 * brief, "loop": brief}, {"roll": 2 * brief, "loop": 0.0}]
    kept = enough_judged(evidence, seconds)
    assert kept.too_little == {"loop": round(brief, 1)}
    assert set(change_thresholds(kept, 1.5, None)[SUM]) == {"roll"}
    assert {j.name for j in change_judges(kept.peaks, kept.judged)} == {"roll"}
    three = ChangeEvidence(["roll", "loop"], [peaks(2.0), peaks(3.0), peaks(1.0)])
    unknown = enough_judged(three, [*seconds, None])
    assert unknown.too_little == {} and set(change_thresholds(unknown, 1.5, None)[SUM]) == {
        "roll", "loop"}


def test_a_signal_judged_below_only_passes_a_rise_and_finds_a_drop(calibrated):
    from auvdiag_cli.jobs.change_calibration import change_evidence
    from models.change_training import TrainedOnPeaks

    residual = _noise(150.0, signals=1, seed=5)
    rise, drop = residual.copy(), residual.copy()
    rise[900:, 0] += 3.0
    drop[900:, 0] -= 3.0
    time_s = np.arange(residual.shape[0]) * DT_S
    limits = {WINDOW_Z: {"speed": 7.0}, SUM: {"speed": 21.0}}

    def checked(values: np.ndarray, below: set[str]) -> ChangeCheck:
        return check_change(values, ["speed"], limits, time_s, WINDOW, DT_S, below_only=below)

    assert checked(rise, set()).alarm_s is not None            # judged either way: found
    assert checked(rise, {"speed"}).alarm_s is None             # below only: no failure
    found = checked(drop, {"speed"})
    assert found.alarm_s is not None and 90.0 <= found.alarm_s < 92.0
    assert found.ways == {"speed": "below"} and not found.loops
    assert "below the prediction" in found.describe()
    # Calibrate leaves out the way above of the logs a model was trained on before the
    # signal was judged below only: that way no longer sets its thresholds.
    model, _ = calibrated
    profile = api.load_profile(None)
    one_way = replace(profile, sensors=tuple(
        replace(s, below_only="why") if s.name == "flow" else s for s in profile.sensors))
    trained = [TrainedOnPeaks(f"log{i}", "0" * 64, {
        statistic: {"flow above": 9.0, "flow below": 3.0 + i,
                    "yaw_rate above": 2.0, "yaw_rate below": 2.0}
        for statistic in (WINDOW_Z, SUM)}) for i in range(3)]
    for shape, expected in ((profile, [9.0, 9.0, 9.0]), (one_way, [3.0, 4.0, 5.0])):
        evidence = change_evidence([], ["flow", "yaw_rate"], model, shape, trained)
        assert [p[SUM]["flow"] for p in evidence.peaks] == expected
        assert [p[SUM]["yaw_rate"] for p in evidence.peaks] == [2.0] * 3


def test_the_plane_judges_what_only_its_engine_moves_below_the_prediction_only():
    profile = api.load_profile("arduplane_carbonz")
    below = {s.name for s in profile.sensors if s.below_only}
    assert below == {"accel_x", "ground_speed"}
    assert all(profile.sensor(name).moved_by == ("engine",) for name in below)
    engine = next(a for a in profile.actuators if a.name == "engine")
    assert all(dict(engine.weakened)[name] == -1 for name in below)   # the way its loss moves them


def test_a_failure_within_the_reference_is_reported_as_possibly_earlier(calibrated, tmp_path):
    """The flow sensor dies 29 s into a dive whose every signal only the change test judges:
    seen once judging begins, at about 31 s; the onset the summary and the JSON report give
    may lie earlier, in the reference, and they say so."""
    from auvdiag_cli.reports.report_build import build_report
    from auvdiag_cli.reports.sentences import when_sentence
    from auvdiag_cli.reports.text import summary_lines
    from auvdiag_cli.simulator.scenarios import get_scenario

    model, _ = calibrated
    base = api.load_profile(None)
    profile = replace(base, sensors=tuple(replace(s, own_log_only="judged against itself")
                                          for s in base.sensors))
    log = tmp_path / "early.mcap"
    api.simulate(get_scenario("mission-flow-sensor-dead", base, 29.0), base, log,
                 log_format="mcap", seed=7)
    diagnosis = api.diagnose(log, profile, model)
    check = diagnosis.change_check
    assert diagnosis.verdict == "fault" and check is not None and check.since_judged
    assert diagnosis.onset_s == check.onset_s and check.onset_s - check.onset_error_s < 1.0
    report = build_report(diagnosis)
    assert report.change_check is not None and report.change_check.onset_in_reference
    (onset,) = [line for line in summary_lines(report) if line.startswith("  onset")]
    assert " or earlier " in onset and onset.endswith(" or more)")
    assert " or earlier, detected at " in when_sentence(report)      # the PDF's words
