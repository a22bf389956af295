"""A loop on an actuator's demand (`[[tracking]]` ``drive``): how much rate a part gives for
what the controller asks of it, read from the output further from neutral, fitted on normal
logs, falling where the part loses authority whether the surface or its output stuck."""

import json

import numpy as np
import pytest

from auvdiag_cli import api
from auvdiag_cli.vehicle.profile import parse_profile, profile_text
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
    import tomllib
    from pathlib import Path

    return tomllib.loads(profile_text(Path("arduplane_carbonz"))[0])


def test_the_plane_profile_judges_the_ailerons_authority_from_their_outputs():
    profile = api.load_profile("arduplane_carbonz")
    loop = next(spec for spec in profile.tracking if spec.drive)
    assert loop.drive == ("aileron_left", "aileron_right") and loop.rate == "roll_rate"
    assert loop.moved_by == ("ailerons",) and set(loop.drive) <= set(profile.output_names)
    assert not set(loop.drive) & set(profile.drive_names)    # the model is not driven by them


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


def test_train_fits_the_authority_from_the_logs_outputs():
    """`train`'s loops read each log's actuator outputs beside its drive; a log without
    them leaves the loop unfitted, and `train` says so."""
    from auvdiag_cli.jobs.tracking_fit import tracking_entry

    profile = api.load_profile("arduplane_carbonz")
    rng = np.random.default_rng(4)
    logs, bare = [], []
    for seed in range(3):
        outputs, rate = _flight(200, seed)
        drive = rng.normal(0, 0.1, (len(rate), len(profile.drive_names)))
        measured = rng.normal(0, 0.1, (len(rate), len(profile.sensor_names)))
        measured[:, profile.sensor_names.index("roll_rate")] = rate[:, 0]
        logs.append(ScoringLog(f"flight{seed}", drive, measured, outputs=outputs))
        bare.append(ScoringLog(f"flight{seed}", drive, measured))
    said: list[str] = []
    entries = {e["name"]: TrackingFit.from_json(e) for e in tracking_entry(profile, logs,
                                                                            said.append)}
    fit = entries["aileron_authority"]
    assert fit.typical == pytest.approx(1.0, rel=0.1) and 1 <= fit.lag_steps <= 3
    assert any(line.startswith("the loop aileron_authority: a gain of") and
               f"per unit of aileron_left or aileron_right asked {fit.lag_steps * DT:.1f} s "
               "before" in line and "from a demand of" in line for line in said)
    said.clear()
    assert "aileron_authority" not in {e["name"] for e in tracking_entry(profile, bare,
                                                                         said.append)}
    assert said[-1] == ("not fitted (the logs never move what they answer): "
                        "aileron_authority")


def test_inspect_says_which_loop_reads_an_output():
    from auvdiag_cli.jobs.inspect import on_grid

    profile = api.load_profile("arduplane_carbonz")
    assert on_grid("aileron_left", 3.0, profile) == (
        "held: the last output at each 0.1 s step, read for the loop aileron_authority only")
