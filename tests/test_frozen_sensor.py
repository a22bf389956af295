"""A sensor whose readings froze at one value from the onset on is named; one still
reading, one pinned at the limit of what it read (saturated), one on a vehicle at rest, or
one that froze far from the onset is not, nor two sensors frozen at once."""

import numpy as np

from auvdiag_cli.engine.frozen_sensor import frozen_sensor
from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.residuals import Matching
from auvdiag_cli.vehicle.profile import Sensor

STEPS, ONSET, WINDOW = 1200, 600, 20
TIME_S = np.arange(STEPS) * 0.1
SENSORS = (Sensor("yaw_rate", "gyro", "rad/s", 1.0, "yaw rate"),
           Sensor("roll_rate", "gyro", "rad/s", 1.0, "roll rate"),
           Sensor("heave", "depth_rate_sensor", "m/s", 1.0, "heave"))


def _turning(rng: np.random.Generator) -> np.ndarray:
    return 0.3 * np.sin(TIME_S / 7.0) + rng.normal(0.0, 0.01, STEPS)


def _histories(measured: np.ndarray, modelled: np.ndarray) -> Histories:
    return Histories(time_s=TIME_S, sensor_names=tuple(s.name for s in SENSORS),
                     matching=Matching(measured, modelled, np.zeros_like(measured)))


def _log(gyro_after: float | None, freeze_at: int = ONSET, model_moves: bool = True
         ) -> Histories:
    rng = np.random.default_rng(3)
    truth = np.column_stack([_turning(rng), 0.1 * _turning(rng), 0.5 * _turning(rng)])
    measured = truth + rng.normal(0.0, 0.002, truth.shape)
    if gyro_after is not None:
        measured[freeze_at:, :2] = gyro_after
    modelled = truth.copy() if model_moves else np.zeros_like(truth)
    return _histories(measured, modelled)


def test_a_gyro_reading_zero_from_the_onset_is_named():
    assert frozen_sensor(SENSORS, _log(0.0), TIME_S[ONSET], WINDOW) == "gyro"
    # An onset dated a second early or late still finds it.
    assert frozen_sensor(SENSORS, _log(0.0), TIME_S[ONSET - 10], WINDOW) == "gyro"
    assert frozen_sensor(SENSORS, _log(0.0), TIME_S[ONSET + 10], WINDOW) == "gyro"


def test_what_is_not_a_frozen_sensor_is_not_named():
    # Still reading.
    assert frozen_sensor(SENSORS, _log(None), TIME_S[ONSET], WINDOW) is None
    # Pinned beyond what it read before: a saturated sensor, it may be.
    assert frozen_sensor(SENSORS, _log(0.5), TIME_S[ONSET], WINDOW) is None
    # The model has the vehicle still: a fine sensor may read one value at rest.
    assert frozen_sensor(SENSORS, _log(0.0, model_moves=False), TIME_S[ONSET], WINDOW) is None
    # Froze a minute after the onset: another event.
    assert frozen_sensor(SENSORS, _log(0.0, freeze_at=ONSET + 300), TIME_S[ONSET],
                         WINDOW) is None
    # Only one of the gyro's two signals froze: the gyro still measures.
    one = _log(None)
    assert one.matching is not None
    one.matching.measured[ONSET:, 0] = 0.0
    assert frozen_sensor(SENSORS, one, TIME_S[ONSET], WINDOW) is None
    # No onset, no replay: nothing to judge.
    assert frozen_sensor(SENSORS, _log(0.0), None, WINDOW) is None
    assert frozen_sensor(SENSORS, Histories(), TIME_S[ONSET], WINDOW) is None


def test_two_sensors_frozen_at_once_name_neither():
    both = _log(0.0)
    assert both.matching is not None
    both.matching.measured[ONSET:, 2] = 0.0
    assert frozen_sensor(SENSORS, both, TIME_S[ONSET], WINDOW) is None


def test_a_reading_resampled_onto_the_grid_still_reads_as_frozen():
    # Held readings interpolated onto the grid differ in their last digits.
    rounded = _log(0.0)
    assert rounded.matching is not None
    rounded.matching.measured[ONSET:, :2] = 0.01 * (1 + 1e-13 * np.sin(np.arange(STEPS - ONSET)))[
        :, None]
    assert frozen_sensor(SENSORS, rounded, TIME_S[ONSET], WINDOW) == "gyro"
    # Sampled slower than the grid: each reading repeats for three steps before it froze.
    slow = _log(None)
    assert slow.matching is not None
    held = np.repeat(slow.matching.measured[::3, :2], 3, axis=0)[:STEPS]
    held[ONSET:] = 0.0
    slow.matching.measured[:, :2] = held
    assert frozen_sensor(SENSORS, slow, TIME_S[ONSET], WINDOW) == "gyro"


def test_a_coarse_reading_that_held_as_long_before_is_not_named():
    # Quantised so coarsely that it held one value for 20 s before: a minute more is no news.
    coarse = _log(None)
    assert coarse.matching is not None
    coarse.matching.measured[:, :2] = np.round(coarse.matching.measured[:, :2] / 0.3) * 0.3
    coarse.matching.measured[ONSET - 200:ONSET, :2] = coarse.matching.measured[ONSET - 200, :2]
    coarse.matching.measured[ONSET:, :2] = 0.0
    assert frozen_sensor(SENSORS, coarse, TIME_S[ONSET], WINDOW) is None
