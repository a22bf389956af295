"""A real engine failure that starts mid-flight, found within seconds and named by the
engine's signature in the change test: the ALFA aircraft (../shared/data/alfa), a model of
two flying days' normal flights and the healthy parts of their failed ones, calibrated
for 5 % of normal flights, judging the third day's flights as a user would."""

import csv

import numpy as np
import pytest
from shared_data import SHARED_DATA

from auvdiag_cli import api
from auvdiag_cli.engine.change_statistics import SUM, WINDOW
from auvdiag_cli.reports.training import calibration_lines

ALFA = SHARED_DATA / "alfa"
DAY = "2018-07-18"
GUARD_S = 1.0          # the healthy part ends this long before the labelled onset


def _labels() -> list[dict[str, str]]:
    with (ALFA / "labels.csv").open(newline="") as stream:
        return list(csv.DictReader(stream))


def _day(row: dict[str, str]) -> str:
    return row["sequence"].split("_")[1][:10]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    work = tmp_path_factory.mktemp("alfa")
    training = [row for row in _labels() if _day(row) != DAY]
    healthy = work / "healthy.csv"
    with healthy.open("w", newline="") as stream:
        out = csv.writer(stream)
        out.writerow(["log", "start", "end"])
        for row in (r for r in training if r["onset_time_ns"]):
            out.writerow([row["sequence"], "",
                          f"{int(row['onset_time_ns']) / 1e9 - GUARD_S:.3f}"])
    parts = api.read_healthy_parts(healthy)
    logs = [ALFA / row["sequence"] for row in training]
    profile = api.load_profile("arduplane_carbonz")
    # The change test's predictor is fitted by least squares whatever reads the replay:
    # the linear model alone is enough for it (the network is then not trained).
    api.train(logs, profile, work / "model", options=api.TrainOptions(
        healthy=parts, keep_unskilled=True, predictors=("linear",)))
    model = api.load_model(work / "model", profile)
    said: list[str] = []        # what calibrate says as it goes, then its report
    result = api.calibrate(logs, profile, model, options=api.CalibrateOptions(
        budget=api.FalseAlarmBudget.parse("0.05"), healthy=parts), progress=said.append)
    return profile, model, [*said, *calibration_lines(result)]


def _judged(calibrated, name: str):
    profile, model, _ = calibrated
    (row,) = [r for r in _labels() if r["sequence"] == name]
    diagnosis = api.diagnose(ALFA / name, profile, model)
    onset = None if not row["onset_time_ns"] else (
        int(row["onset_time_ns"]) - diagnosis.start_ns) / 1e9
    return diagnosis, onset


@pytest.mark.shared_data("alfa")
def test_calibrate_sets_the_engine_signatures_thresholds(calibrated):
    _, model, said = calibrated
    for statistic in (WINDOW, SUM):
        assert model.card.change_thresholds[statistic]["engine weakened"] > 0
        # The climb, moved by rising and sinking air, is judged only within the signature,
        # and calibrate says so where it lists the thresholds it set.
        assert "climb" not in model.card.change_thresholds[statistic]
    assert ("  change test: climb judged only within engine weakened, no threshold of its own "
            "(rising and sinking air moves it with no failure)") in said
    # Signals the replay leaves to the change test keep the profile's thresholds for that
    # reason, not for want of skill.
    assert ("    roll, pitch, roll_rate, pitch_rate, yaw_rate: skipped, judged only "
            "against the log's own beginning (replayed from the set points, it drifts with "
            "every manoeuvre); the profile's thresholds stay (15 %)") in said
    assert ("    accel_x: skipped, judged only against the log's own beginning (replayed from "
            "the set points, it drifts with every manoeuvre), only below the prediction (no "
            "failure of its parts lifts it: thrust lost lowers it, a throttle-up lifts it); "
            "the profile's threshold 15 % stays") in said
    assert not any("cannot predict" in line for line in said)
    # Two days' flights tell how far normal flying goes each way, and each way is scaled
    # by it; the forward acceleration, judged below the prediction only (throttle-ups push
    # it above), has its thresholds set on that way alone.
    scales = model.card.change_way_scales[SUM]
    assert "accel_x" not in scales and scales
    assert all(a * b == pytest.approx(1.0, abs=1e-3) for a, b in scales.values())
    assert model.card.change_thresholds[SUM]["accel_x"] > 0


@pytest.mark.shared_data("alfa")
@pytest.mark.parametrize(("name", "within_s"), [
    ("carbonZ_2018-07-18-15-53-31_1_engine_failure", 4.0),
    ("carbonZ_2018-07-18-15-53-31_2_engine_failure", 4.0),
    ("carbonZ_2018-07-18-16-22-01_engine_failure_with_emr_traj", 4.0)])
def test_an_engine_cut_mid_flight_is_found_within_seconds_and_named(calibrated, name,
                                                                     within_s):
    """Each signal the cut moves stays under its own thresholds for many seconds; the four
    together, predicted a moment ahead from a state that holds the airspeed the autopilot
    answers, cross 2.3-2.7 s after the onset and name the engine."""
    diagnosis, onset = _judged(calibrated, name)
    assert (str(diagnosis.verdict), diagnosis.component) == ("fault", "engine")
    assert onset is not None and onset <= diagnosis.detected_at_s <= onset + within_s
    assert "engine weakened" in diagnosis.change_check.evidence


@pytest.mark.shared_data("alfa")
def test_the_days_normal_flight_raises_nothing(calibrated):
    diagnosis, _ = _judged(calibrated, "carbonZ_2018-07-18-12-10-11_no_ground_truth")
    assert str(diagnosis.verdict) == "normal"
    # The flight logs its airspeed as 0 throughout: the change test says it predicted that
    # flight with less than its calibration flights had.
    assert any(n.startswith("change test: airspeed not fed") for n in diagnosis.notes)


@pytest.mark.shared_data("alfa")
def test_the_set_points_are_drawn_in_their_unit(calibrated):
    from auvdiag_cli.reports.pdf.plots import commands_page
    from auvdiag_cli.reports.report_build import build_report
    from auvdiag_cli.reports.series import series_from_diagnosis

    diagnosis, _ = _judged(calibrated, "carbonZ_2018-07-18-15-53-31_2_engine_failure")
    assert diagnosis.sensor_units["roll_sp"] == "rad"
    figure = commands_page(build_report(diagnosis), series_from_diagnosis(diagnosis))
    assert figure.axes[0].get_ylabel() == "command [rad]"


@pytest.mark.shared_data("alfa")
def test_the_report_draws_the_failures_effect_where_the_model_predicts(calibrated):
    """The model of the healthy aircraft replayed from the onset, beside what it did: drawn
    in each signal the model predicts, never in one it cannot (its values would be a
    guess), and said so in the note."""
    from auvdiag_cli.engine.judging import unpredicted
    from auvdiag_cli.reports.pdf.plots import effect_page, residual_page
    from auvdiag_cli.reports.report_build import build_report
    from auvdiag_cli.reports.series import series_from_diagnosis

    _, model, _ = calibrated
    diagnosis, _ = _judged(calibrated, "carbonZ_2018-07-18-15-53-31_1_engine_failure")
    healthy, time_s = diagnosis.healthy_from_onset, diagnosis.histories.time_s
    names = diagnosis.histories.sensor_names
    assert healthy is not None and diagnosis.change_check is not None
    cannot = unpredicted(model)
    drawn = [n for i, n in enumerate(names) if np.isfinite(healthy[:, i]).any()]
    assert drawn and set(drawn) == set(names) - set(cannot)
    assert np.isnan(healthy[time_s < diagnosis.change_check.onset_s - 0.05]).all()
    report, series = build_report(diagnosis), series_from_diagnosis(diagnosis)
    figure = effect_page(report, series)
    assert figure is not None
    # Every signal is left to the change test: no page of g curves that raise nothing.
    assert residual_page(report, series) is None
    assert [ax.get_ylabel().split("\n")[0] for ax in figure.axes] == drawn
    # Close up: from a little before the onset to a little after the replay from it ends.
    replayed = time_s[np.isfinite(healthy).any(axis=1)]
    low, high = figure.axes[0].get_xlim()
    assert replayed[0] - 10.2 <= low < replayed[0] <= replayed[-1] <= high <= replayed[-1] + 10.2
    (note,) = [n for n in diagnosis.notes if n.startswith("found by the change test")]
    unsaid = note.split("cannot say what ")[1].split(" would have done")[0].split(", ")
    assert unsaid and set(unsaid) == set(cannot) & set(diagnosis.change_check.changed)


@pytest.mark.shared_data("alfa")
def test_a_flight_too_short_for_its_own_reference_is_undetermined_and_says_why(calibrated):
    """Every signal of this profile is judged against the flight's own beginning only, and
    the change test needs 30 s of it: a 29.5 s sequence is not judged, not called normal."""
    diagnosis, _ = _judged(calibrated, "carbonZ_2018-07-18-16-37-39_1_no_failure")
    assert str(diagnosis.verdict) == "undetermined"
    assert ("no signal is judged: 8 of 8 are judged only against the log's own beginning, "
            "by the change test, and it is not judged (the log is too short: needs 30 s of "
            "its own residuals as its reference)") in diagnosis.notes


@pytest.mark.shared_data("alfa")
def test_a_flight_without_its_airspeed_is_judged_by_thresholds_set_without_it(calibrated):
    """Calibrate replays its normal flights with the airspeed held at its typical value as
    well: the predictor then errs further on some signals (the climb follows the airspeed),
    and a flight that logs no airspeed is judged against those thresholds where higher."""
    _, model, _ = calibrated
    unfed = model.card.change_unfed["airspeed"]
    fed = model.card.change_thresholds
    raised = [(s, n) for s, values in unfed.items() for n, v in values.items() if v > fed[s][n]]
    assert raised and len(raised) == sum(len(v) for v in unfed.values())
    # The flights of 2018-09-11, which logged no airspeed, count as they are beside the
    # others replayed with it held.
    fed_days = sum(_day(r) == "2018-07-30" for r in _labels())
    without = sum(_day(r) == "2018-09-11" for r in _labels())
    assert (f"the change test with airspeed held, on {fed_days} normal log(s) and {without} "
            "without it") in calibrated[2]
    # The roll loop's gain reads no input: a flight without airspeed is judged on it as any.
    assert model.card.change_thresholds[SUM]["roll_tracking"] > 0
    assert all("roll_tracking" not in values for values in unfed.values())
    # calibrate says what it set for such a log.
    (said,) = [line for line in calibrated[2] if "change test for a log without airspeed" in line]
    statistic, name = raised[0]
    assert f"{statistic} " in said and f"{name} {unfed[statistic][name]:g}" in said
    without = model.card.change_thresholds_without(["airspeed"])
    assert all(without[s][n] == unfed[s][n] for s, n in raised)
    assert model.card.change_thresholds_without([]) == {s: dict(v) for s, v in fed.items()}
    diagnosis, _ = _judged(calibrated, "carbonZ_2018-07-18-12-10-11_no_ground_truth")
    assert any(n.startswith("change test: airspeed not fed in this log: judged against the "
                            "thresholds calibrate set") for n in diagnosis.notes)
    check = diagnosis.change_check
    assert check is not None
    statistic, name = next((s, n) for s, n in raised if n in check.thresholds.get(s, {}))
    assert check.thresholds[statistic][name] == pytest.approx(unfed[statistic][name])


@pytest.mark.shared_data("alfa")
def test_a_stuck_aileron_slows_the_roll_loop(calibrated):
    """The profile's roll loop, fitted on the normal flights: the roll rate per radian of
    roll error. One aileron stuck (the other still moving) leaves the roll following its
    set point, only slower: the loop's gain falls from the onset and stays low."""
    profile, model, _ = calibrated
    (loop,) = model.card.tracking
    assert 0 <= loop.lag_steps <= 10 and 0.5 < loop.typical < 1.5
    assert 0 < loop.floor < loop.limit
    assert model.card.change_thresholds[SUM]["roll_tracking"] > 0
    diagnosis, onset = _judged(calibrated, "carbonZ_2018-09-11-17-55-30_2_left_aileron_failure")
    histories = diagnosis.histories
    gain = histories.change_residual[:, histories.change_names.index("roll_tracking")]
    time_s = histories.time_s
    before = gain[(time_s > 20) & (time_s < onset)]
    after = gain[time_s > onset + loop.window_steps * profile.dt_s]
    assert abs(np.nanmedian(before)) < 0.15 < -np.nanmedian(after)
    assert np.nanmax(after) < np.nanpercentile(before, 10)


@pytest.mark.shared_data("alfa")
def test_three_short_normal_flights_leave_the_roll_loop_unjudged_and_say_so(tmp_path):
    """A day's three normal flights (33, 43 and 67 s) let the change test judge the roll
    loop's gain for 15.6 s in all: too little to set its thresholds, which at the floors had
    it alarm before anything failed on flights of other days. Calibrate says so, and the
    predictor a moment ahead, shrunk to what three flights pin down, still predicts every
    signal better than "no change"."""
    flights = [ALFA / row["sequence"] for row in _labels()
               if _day(row) == "2018-09-11" and not row["onset_time_ns"]]
    assert len(flights) == 3
    profile = api.load_profile("arduplane_carbonz")
    api.train(flights, profile, tmp_path / "model", options=api.TrainOptions(
        keep_unskilled=True, predictors=("linear",)))
    model = api.load_model(tmp_path / "model", profile)
    assert model.card.ahead is not None and min(model.card.ahead.skill.values()) > 0.1
    result = api.calibrate(flights, profile, model, options=api.CalibrateOptions(
        budget=api.FalseAlarmBudget.parse("0.05")))
    assert set(result.change_too_little) == {"roll_tracking"}
    assert all("roll_tracking" not in limits for limits in result.change.values())
    assert any(line.startswith("  change test: no thresholds (not judged) where these logs")
               and line.endswith("roll_tracking 15.6 s") for line in calibration_lines(result))


@pytest.mark.shared_data("alfa")
def test_a_flight_recorded_on_a_clock_days_off_is_dated_by_its_gps_time(calibrated):
    """Four sequences of 2018-07-30 were received on a clock 9.8 days behind the GPS time
    they carry: their UTC times are the GPS's, their seconds the log's own, and the model
    calibrated on that day's flights knows the day as 2018-07-30, not 2018-07-21."""
    from auvdiag_cli.reports.report_build import build_report

    _, model, _ = calibrated
    assert model.card.calibration_days == ("2018-07-30", "2018-09-11")
    diagnosis, onset = _judged(calibrated,
                               "carbonZ_2018-07-30-16-29-45_engine_failure_with_emr_traj")
    report = build_report(diagnosis)
    assert report.start_time_utc is not None and report.start_time_utc.startswith(
        "2018-07-30T20:24:5")
    assert any(n.startswith("the log's clock runs 9.8 days behind the UTC time it carries")
               for n in diagnosis.notes)
    assert onset is not None and 0 < diagnosis.detected_at_s - onset < 10
    # inspect says so, and that its span (what --healthy takes) is on the log's own clock.
    inspection = api.inspect(ALFA / "carbonZ_2018-07-30-16-29-45_engine_failure_with_emr_traj",
                             calibrated[0])
    assert any(w.startswith("the log's clock runs 9.8 days behind") and w.endswith(
        "the span above is on the log's own clock, as --healthy takes it")
        for w in inspection.warnings)
    # Another day's flight on a clock that kept time: nothing said, nothing moved.
    other, _ = _judged(calibrated, "carbonZ_2018-07-30-17-10-45_engine_failure_with_emr_traj")
    assert other.utc_offset_ns == 0 and not any("clock runs" in n for n in other.notes)


def _frozen_copy(folder, into, fields: dict[str, tuple[str, ...]], from_s: float):
    """The flight's CSV folder with the named fields of each topic file (by the end of its
    name) reading, from ``from_s`` on, the value they read then."""
    copy = into / folder.name
    copy.mkdir()
    for path in folder.glob("*.csv"):
        rows = list(csv.reader(path.open(newline="")))
        frozen = [rows[0].index(f"field.{name}")
                  for end, names in fields.items() if path.stem.endswith(end) for name in names]
        start, held = int(rows[1][0]), None
        for row in rows[1:]:
            if frozen and int(row[0]) - start >= from_s * 1e9:
                held = held or [row[i] for i in frozen]
                for i, value in zip(frozen, held, strict=True):
                    row[i] = value
        with (copy / path.name).open("w", newline="") as stream:
            csv.writer(stream).writerows(rows)
    return copy


@pytest.mark.shared_data("alfa")
@pytest.mark.parametrize(("fields", "sensor"), [
    ({"imu-data_raw": ("angular_velocity.x", "angular_velocity.y", "angular_velocity.z")},
     "gyro"),
    ({"nav_info-roll": ("measured",), "nav_info-pitch": ("measured",)}, "ahrs")])
def test_a_sensor_that_freezes_mid_flight_is_named(calibrated, tmp_path, fields, sensor):
    """A real flight whose gyro (three rates at 10 Hz, read onto the model's grid by
    interpolation) or attitude (read at about 4 Hz: a reading repeats on the grid) reads one
    value from 100 s on: the change test sees the motion depart from the prediction, and
    the sensor that froze is named, not the part that moves what changed."""
    profile, model, _ = calibrated
    flight = _frozen_copy(ALFA / "carbonZ_2018-07-18-12-10-11_no_ground_truth", tmp_path,
                          fields, 100.0)
    diagnosis = api.diagnose(flight, profile, model)
    assert (str(diagnosis.verdict), diagnosis.component) == ("fault", sensor)
    assert 100.0 <= diagnosis.detected_at_s <= 105.0
    assert any("froze at one value" in note for note in diagnosis.notes)


def _cropped_copy(folder, tmp_path, from_ns: int):
    """The flight's CSV folder from ``from_ns`` on (each topic's rows received then or
    later), as a recording begun then would hold it."""
    copy = tmp_path / folder.name
    copy.mkdir()
    for path in folder.glob("*.csv"):
        rows = list(csv.reader(path.open(newline="")))
        with (copy / path.name).open("w", newline="") as stream:
            csv.writer(stream).writerows([rows[0], *(r for r in rows[1:]
                                                     if int(r[0]) >= from_ns)])
    return copy


@pytest.mark.shared_data("alfa")
def test_a_failure_inside_the_reference_is_found_but_not_named_alone(calibrated, tmp_path):
    """An engine cut 20 s into a recording: within the 30 s of its own beginning the change
    test takes as its reference, where the cut's first effect (the forward acceleration
    falling) is absorbed. What changes after judging begins may be the aircraft's answer
    (on another day's engine cut so placed, the roll changed most, and "ailerons" was
    named): the verdict gives the two likeliest parts and says why it names neither alone."""
    profile, model, _ = calibrated
    name = "carbonZ_2018-07-18-15-53-31_1_engine_failure"
    (row,) = [r for r in _labels() if r["sequence"] == name]
    onset_ns = int(row["onset_time_ns"])
    flight = _cropped_copy(ALFA / name, tmp_path, onset_ns - 20 * 10**9)
    diagnosis = api.diagnose(flight, profile, model)
    check = diagnosis.change_check
    assert str(diagnosis.verdict) == "fault" and check is not None and check.since_judged
    assert diagnosis.component is None and len(diagnosis.candidates) == 2
    assert "engine" in diagnosis.candidates
    assert any("no one part is named: the change may have begun before the first step "
               "judged" in note for note in diagnosis.notes)
