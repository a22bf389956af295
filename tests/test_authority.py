"""A loop on an actuator's demand (`[[tracking]]` ``drive``): how much rate a part gives for
what the controller asks of it, read from the output further from neutral, fitted on normal
logs, falling where the part loses authority whether the surface or its output stuck."""

import csv
import json

import numpy as np
import pytest
from shared_data import SHARED_DATA

from auvdiag_cli.vehicle.profile import Profile, parse_profile, profile_text
from auvdiag_errors import ProfileError
from models.skill import ScoringLog
from models.tracking import TrackingFit, TrackingSpec, demand, fit_tracking

DT = 0.1
SPEC = TrackingSpec("aileron_authority", None, None, "roll_rate", ("ailerons",),
                    drive=("aileron_left", "aileron_right"), window_s=5.0)
OUTPUTS, SENSORS = ("aileron_left", "aileron_right"), ("roll_rate",)


def _flight(seconds: float, seed: int, stuck_from_s: float | None = None,
            held_output: bool = False, lag: int = 2, trim: float = 0.0
            ) -> tuple[np.ndarray, np.ndarray]:
    """Two ailerons driven alike by a demand that changes every 3 s; the roll rate ``lag``
    steps later answers both surfaces' deflections. From ``stuck_from_s`` the left surface
    sticks at neutral: its output still moves with the demand (a real stuck surface) or is
    held at neutral as well (``held_output``: an autopilot emulating the failure). The
    outputs hold the surfaces' ``trim``: what leaves the rate at zero."""
    rng = np.random.default_rng(seed)
    n = round(seconds / DT)
    asked = np.repeat(rng.uniform(-0.4, 0.4, n // 30 + 1), 30)[:n]
    left_surface, right = asked.copy(), asked.copy()
    left_output = asked.copy()
    if stuck_from_s is not None:
        stuck = np.arange(n) * DT >= stuck_from_s
        left_surface[stuck] = 0.0
        if held_output:
            left_output[stuck] = 0.0
    rate = np.zeros(n)
    rate[lag:] = 0.5 * (left_surface + right)[:-lag]
    rate += rng.normal(0, 0.01, n)
    return np.column_stack([left_output, right]) + trim, rate[:, None]


def _fit() -> TrackingFit:
    (fit,) = fit_tracking([SPEC], [_flight(200, seed) for seed in range(3)], OUTPUTS, SENSORS,
                          DT)
    return fit


def test_the_demand_is_the_output_further_from_neutral():
    outputs = np.array([[0.2, 0.3], [-0.5, 0.1], [0.0, -0.4], [np.nan, 0.2],
                        [np.nan, np.nan]])
    assert demand(outputs)[:4] == pytest.approx([0.3, -0.5, -0.4, 0.2])
    assert np.isnan(demand(outputs)[4])


def test_a_drive_loop_is_fitted_with_its_lag_window_and_authority():
    fit = _fit()
    assert fit.drive == SPEC.drive and fit.set_point is None and fit.measured is None
    assert fit.lag_steps == 2 and fit.window_steps == 50
    assert fit.typical == pytest.approx(1.0, rel=0.05)
    assert TrackingFit.from_json(json.loads(json.dumps(fit.to_json()))) == fit


@pytest.mark.parametrize("held_output", [False, True])
def test_the_authority_halves_where_a_surface_sticks_whichever_way_its_output_reads(
        held_output):
    fit = _fit()
    outputs, rate = _flight(200, 9, stuck_from_s=100, held_output=held_output)
    gain = fit.gain(outputs, rate, OUTPUTS, SENSORS, DT) + fit.typical
    before, after = gain[100:990], gain[1060:]
    assert np.nanmin(before) > 0.9 and np.nanmax(after) < 0.6
    assert np.nanmedian(after) == pytest.approx(0.5, rel=0.1)


def test_a_log_read_without_the_outputs_leaves_the_authority_unjudged():
    fit = _fit()
    _, rate = _flight(100, 11)
    assert np.isnan(fit.gain(np.zeros((len(rate), 1)), rate, ("roll_sp",), SENSORS, DT)).all()


def test_a_trimmed_part_keeps_its_authority_where_little_is_asked():
    """A demand offset by the part's trim is judged by how the rate follows its changes:
    straight flight (little asked beyond the trim) is not read as lost authority."""
    fit = _fit()
    outputs, rate = _flight(200, 10, trim=0.1)
    outputs[1000:1200] = 0.1 + np.random.default_rng(1).normal(0, 0.15, (200, 1))
    rate[1000 + 2:1200, 0] = 0.5 * 2 * (outputs[1000:1198, 0] - 0.1)
    gain = fit.gain(outputs, rate, OUTPUTS, SENSORS, DT) + fit.typical
    straight = gain[1000 + fit.window_steps + fit.lag_steps:1200]
    assert np.isfinite(straight).all() and straight.min() > 0.9
    assert np.nanmin(gain[100:990]) > 0.9


def _plane_document() -> dict:
    """`arduplane_carbonz` with the ailerons' authority: the two aileron outputs (ALFA's
    `rc/out` channels 5 and 6, PWM about 1500 us) and the loop on their demand."""
    import tomllib
    from pathlib import Path

    data = tomllib.loads(profile_text(Path("arduplane_carbonz"))[0])
    data["outputs"] = [{"name": name, "component": "ailerons", "kind": "control_surface",
                        "unit": "1"} for name in OUTPUTS]
    data["tracking"].append({"name": "aileron_authority", "drive": list(OUTPUTS),
                             "rate": "roll_rate", "moved_by": ["ailerons"], "window_s": 5.0})
    for channel, name in enumerate(OUTPUTS, start=4):
        data["sources"]["ros"]["signals"][name] = {
            "topic": "/mavros/rc/out", "field": f"channels[{channel}]", "scale": 0.002,
            "offset": -3.0}
    return data


@pytest.fixture(scope="module")
def plane() -> Profile:
    return parse_profile(_plane_document(), "plane with the ailerons' authority")


def test_a_plane_profile_reads_the_ailerons_authority_from_their_outputs(plane):
    loop = next(spec for spec in plane.tracking if spec.drive)
    assert loop.drive == OUTPUTS and loop.rate == "roll_rate" and loop.window_s == 5.0
    assert loop.moved_by == ("ailerons",) and set(loop.drive) <= set(plane.output_names)
    assert not set(loop.drive) & set(plane.drive_names)    # the model is not driven by them


@pytest.mark.parametrize(("entry", "message"), [
    ({"set_point": "roll_sp"}, "not both"),
    ({"rate": None}, "needs its 'rate'"),
    ({"drive": ["aileron_left", "elevator_out"]}, "names no output or command"),
    ({"window_s": -1.0}, "must be positive")])
def test_a_drive_loop_the_profile_cannot_read_is_refused(entry, message):
    data = _plane_document()
    (index,) = [i for i, row in enumerate(data["tracking"]) if "drive" in row]
    row = {**data["tracking"][index], **entry}
    data["tracking"][index] = {k: v for k, v in row.items() if v is not None}
    with pytest.raises(ProfileError, match=message):
        parse_profile(data, "test")


def test_train_fits_the_authority_from_the_logs_outputs(plane):
    """`train`'s loops read each log's actuator outputs beside its drive; a log without
    them leaves the loop unfitted, and `train` says so."""
    from auvdiag_cli.jobs.tracking_fit import tracking_entry

    rng = np.random.default_rng(4)
    logs, bare = [], []
    for seed in range(3):
        outputs, rate = _flight(200, seed)
        drive = rng.normal(0, 0.1, (len(rate), len(plane.drive_names)))
        measured = rng.normal(0, 0.1, (len(rate), len(plane.sensor_names)))
        measured[:, plane.sensor_names.index("roll_rate")] = rate[:, 0]
        logs.append(ScoringLog(f"flight{seed}", drive, measured, outputs=outputs))
        bare.append(ScoringLog(f"flight{seed}", drive, measured))
    said: list[str] = []
    entries = {e["name"]: TrackingFit.from_json(e) for e in tracking_entry(plane, logs,
                                                                            said.append)}
    fit = entries["aileron_authority"]
    assert fit.typical == pytest.approx(1.0, rel=0.1) and 1 <= fit.lag_steps <= 3
    assert any(line.startswith("the loop aileron_authority: a gain of") and
               f"per unit of aileron_left or aileron_right asked {fit.lag_steps * DT:.1f} s "
               "before" in line and "from a demand of" in line for line in said)
    said.clear()
    assert "aileron_authority" not in {e["name"] for e in tracking_entry(plane, bare,
                                                                         said.append)}
    assert said[-1] == ("not fitted (the logs never move what they answer): "
                        "aileron_authority")


def test_inspect_says_which_loop_reads_an_output(plane):
    from auvdiag_cli.jobs.inspect import on_grid

    assert on_grid("aileron_left", 3.0, plane) == (
        "held: the last output at each 0.1 s step, read for the loop aileron_authority only")


ALFA = SHARED_DATA / "alfa"


@pytest.mark.shared_data("alfa")
def test_a_stuck_aileron_lowers_the_ailerons_authority_on_real_flights(plane):
    """Fitted on ALFA's normal flights: where the autopilot holds the failed aileron's
    output at neutral, the other output carries the demand, and from the first roll asked
    after the failure the same demand brings about two thirds of the rate it brought
    before (the right aileron: a roll asked within 1 s; the left: 9 s after)."""
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.jobs.tracking_fit import tracking_entry
    from auvdiag_cli.jobs.training_logs import read_for_training

    with (ALFA / "labels.csv").open(newline="") as stream:
        rows = {row["sequence"]: row for row in csv.DictReader(stream)}
    normal = [read_for_training(ALFA / name, plane, lambda _: None).scoring
              for name, row in rows.items() if row["kind"] == "normal"]
    (entry,) = [e for e in tracking_entry(plane, normal) if e["name"] == "aileron_authority"]
    fit = TrackingFit.from_json(entry)
    assert 0 <= fit.lag_steps <= 10 and fit.window_steps == 50 and fit.typical > 0
    for name, first_roll_s in (("carbonZ_2018-09-11-17-55-30_1_right_aileron_failure", 1.0),
                               ("carbonZ_2018-09-11-17-55-30_2_left_aileron_failure", 9.0)):
        log = ingest(ALFA / name, plane)
        frame = log.frame
        gain = fit.gain(np.hstack([frame.commands, frame.outputs]), frame.sensors,
                        [*frame.command_names, *frame.output_names], frame.sensor_names,
                        frame.dt_s) + fit.typical
        onset = (int(rows[name]["onset_time_ns"]) - log.signals.start_ns) / 1e9
        before = gain[(frame.time_s > 20) & (frame.time_s < onset)]
        after = gain[(frame.time_s > onset + first_roll_s)
                     & (frame.time_s < onset + first_roll_s + 10)]
        assert np.isfinite(after).sum() > 50, name
        assert np.nanmedian(after) < 0.75 * np.nanmedian(before), name
        assert np.nanmedian(after) < np.nanpercentile(before, 10), name
