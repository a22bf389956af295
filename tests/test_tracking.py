"""A loop of the controller judged by its gain: how much rate an error brings, fitted on
normal logs, re-estimated along a log, judged below its usual value only."""

import json

import numpy as np
import pytest

from auvdiag_cli import api
from auvdiag_cli.engine.change_check import check_change
from auvdiag_cli.engine.change_statistics import SUM, WINDOW, way_statistics
from auvdiag_cli.vehicle.profile import parse_profile, profile_text
from auvdiag_errors import ProfileError
from models.tracking import TrackingFit, TrackingSpec, fit_tracking

DT = 0.1
SPEC = TrackingSpec("roll_tracking", "roll_sp", "roll", "roll_rate", ("ailerons",))
COMMANDS, SENSORS = ("roll_sp",), ("roll", "roll_rate")


def _flight(seconds: float, gain: float, seed: int, weak_from_s: float | None = None,
            weak_gain: float = 0.5, lag: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """A roll loop: the rate ``lag`` steps later is ``gain`` times the error (times
    ``weak_gain`` from ``weak_from_s``), with noise; the set point steps every few seconds."""
    rng = np.random.default_rng(seed)
    n = round(seconds / DT)
    set_point = np.repeat(rng.uniform(-0.6, 0.6, n // 40 + 1), 40)[:n]
    roll, rate = np.zeros(n), np.zeros(n)
    for k in range(1, n):
        source = max(k - lag, 0)
        now = gain * (weak_gain if weak_from_s is not None and k * DT >= weak_from_s else 1.0)
        rate[k] = now * (set_point[source] - roll[source]) + rng.normal(0, 0.02)
        roll[k] = roll[k - 1] + rate[k] * DT
    return set_point[:, None], np.column_stack([roll, rate])


def _fit(logs: list[tuple[np.ndarray, np.ndarray]]) -> TrackingFit:
    (fit,) = fit_tracking([SPEC], logs, COMMANDS, SENSORS, DT)
    return fit


def test_the_fit_finds_the_loops_lag_and_its_gain():
    fit = _fit([_flight(300, 1.2, seed) for seed in range(3)])
    assert fit.lag_steps == 2 and fit.window_steps == 100
    assert fit.typical == pytest.approx(1.2, rel=0.05) and fit.floor > 0
    assert TrackingFit.from_json(json.loads(json.dumps(fit.to_json()))) == fit


def test_the_gain_falls_where_a_part_weakens_and_nowhere_else():
    fit = _fit([_flight(300, 1.2, seed) for seed in range(3)])
    commands, sensors = _flight(300, 1.2, 7, weak_from_s=150)
    gain = fit.gain(commands, sensors, COMMANDS, SENSORS, DT) + fit.typical
    before, after = gain[200:1450], gain[1600:]
    assert np.nanmin(before) > 1.0 and np.nanmax(after) < 0.8
    assert np.nanmedian(after) == pytest.approx(0.6, rel=0.1)


def test_a_window_without_error_enough_is_not_judged():
    fit = _fit([_flight(300, 1.2, seed) for seed in range(3)])
    commands, sensors = _flight(100, 1.2, 8)
    commands[:] = 0.0
    sensors[:] = 0.0
    assert np.isnan(fit.gain(commands, sensors, COMMANDS, SENSORS, DT)).all()


def test_a_loop_is_judged_below_only():
    rng = np.random.default_rng(3)
    residual = rng.normal(0, 0.05, (1200, 2))
    residual[700:, 0] += 0.5          # the first column rises, the second falls
    residual[700:, 1] -= 0.5
    statistics = way_statistics(residual, 10, 300, below_only=[0, 1])
    above, below = statistics[SUM][:, :2], statistics[SUM][:, 2:]
    assert np.isnan(above).all()
    assert np.nanmax(below[:, 1]) > 20 > np.nanmax(below[:, 0])
    names = ["roll_tracking", "yaw_tracking"]
    thresholds = {WINDOW: {n: 8.0 for n in names}, SUM: {n: 15.0 for n in names}}
    check = check_change(residual, names, thresholds, np.arange(1200) * DT, 10, DT,
                         loops=set(names))
    assert check.alarm_s is not None and 70.0 <= check.alarm_s < 72.0
    assert set(check.flagged) == {"yaw_tracking"} and not check.ways
    assert "yaw_tracking" in check.describe() and "less rate than usual" in check.describe()


def test_the_plane_profile_declares_its_roll_loop():
    profile = api.load_profile("arduplane_carbonz")
    loop = next(spec for spec in profile.tracking if spec.name == "roll_tracking")
    assert (loop.set_point, loop.measured, loop.rate, loop.moved_by) == (
        "roll_sp", "roll", "roll_rate", ("ailerons",))


@pytest.mark.parametrize(("entry", "message"), [
    ({"set_point": "depth"}, "names no command"),
    ({"measured": "nothing"}, "names no sensor"),
    ({"name": "roll"}, "already the name of a signal"),
    ({"moved_by": ["propeller"]}, "no actuator or command component")])
def test_a_loop_that_names_what_the_profile_lacks_is_refused(entry, message):
    data = _plane_document()
    data["tracking"] = [{**data["tracking"][0], **entry}, *data["tracking"][1:]]
    with pytest.raises(ProfileError, match=message):
        parse_profile(data, "test")


def _plane_document() -> dict:
    import tomllib
    from pathlib import Path

    return tomllib.loads(profile_text(Path("arduplane_carbonz"))[0])


def test_train_fits_the_plane_profiles_loop_and_says_what_it_fitted():
    """The profile's roll loop on logs of the plane's signals (the other signals noise): the
    lag is one at which the error foretells the rate nearly as well as at the best, and
    `train` says the gain, the lag and the limits it fitted."""
    from auvdiag_cli.jobs.tracking_fit import tracking_entry
    from models.skill import ScoringLog

    profile = api.load_profile("arduplane_carbonz")
    rng = np.random.default_rng(5)
    logs = []
    for seed in range(3):
        commands, sensors = _flight(300, 1.2, seed)
        drive = rng.normal(0, 0.1, (len(commands), len(profile.drive_names)))
        drive[:, profile.drive_names.index("roll_sp")] = commands[:, 0]
        measured = rng.normal(0, 0.1, (len(commands), len(profile.sensor_names)))
        for column, name in enumerate(SENSORS):
            measured[:, profile.sensor_names.index(name)] = sensors[:, column]
        logs.append(ScoringLog(f"flight{seed}", drive, measured))
    said: list[str] = []
    (entry,) = tracking_entry(profile, logs, said.append)
    fit = TrackingFit.from_json(entry)
    assert fit.name == "roll_tracking" and 1 <= fit.lag_steps <= 3
    assert fit.typical == pytest.approx(1.2, rel=0.1) and fit.floor < fit.limit
    assert said == [f"the loop roll_tracking: a gain of {fit.typical:.3g} (the rate per unit "
                    f"of error {fit.lag_steps * 0.1:.1f} s before), judged over 10 s windows "
                    f"from an error of {fit.floor:.3g} rms, errors beyond {fit.limit:.3g} left "
                    "out (saturated)"]
