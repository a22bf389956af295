"""A sensor whose readings froze at the onset: every one of its signals reads one value from
then on, for far longer than it ever held one value before, while the model of the healthy
vehicle has the motion it measures go on moving. No motion gives such a reading; a dead or
stuck sensor does. It names the sensor where no single-component fault explains the log:
under a closed loop the controller acts on the frozen reading, so the vehicle's motion
changes too and the replay of "that sensor dead" does not explain the rest (on the
simulated BlueROV2 a dead gyro left its heave at three times its threshold). Where the
change test alone found the change (a profile that judges its signals only against the
log's own beginning), it names the sensor before the parts that move what changed: on an
ALFA flight whose gyro was made to freeze, the roll and yaw rates departed from the
prediction and the rudder had been named."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.results import Observations
from auvdiag_cli.vehicle.profile import Sensor

# How a report says why the sensor is named.
FROZEN_WHY = ("the sensor whose every reading froze at one value from the onset on, while the "
              "model of the healthy vehicle has what it measures move")
# The frozen stretch is this many times longer than any stretch of one value before it: a
# sensor sampled slower than the model's grid, or quantised, repeats its reading for a few
# steps at a time (on ALFA the attitude, at about 4 Hz on a 10 Hz grid), never for a minute.
LONGER_THAN_BEFORE = 5
# A step this small against the reading is rounding, not a change.
ROUNDING = 1e-9
# The model's motion after the onset spans this many of the reading's typical steps before:
# a vehicle at rest leaves a fine sensor reading one value as well.
MODEL_MOVES_STEPS = 10.0


def frozen_in(seen: Observations, onset_s: float | None, judging: Judging) -> str | None:
    """`frozen_sensor` of the profile's sensors on a diagnosed log."""
    return frozen_sensor(judging.profile.sensors, seen.histories, onset_s, seen.window_samples)


def frozen_sensor(sensors: Sequence[Sensor], histories: Histories, onset_s: float | None,
                  window: int) -> str | None:
    """The sensor component every signal of which froze within ``window`` steps of
    ``onset_s`` (an onset dated from a window's residual may come a little early) and read
    one value to the log's end, for a window or more and within the range it read before (a
    reading pinned at its limit may be a saturated sensor), at least one of them where the
    model moves, where one sensor did; else None."""
    matching = histories.matching
    if matching is None or onset_s is None:
        return None
    onset = int(np.searchsorted(histories.time_s, onset_s))
    column = {name: i for i, name in enumerate(histories.sensor_names)}
    frozen = []
    for component in dict.fromkeys(s.component for s in sensors):
        signals = [column[s.name] for s in sensors
                   if s.component == component and s.name in column]
        states = [_frozen(matching.measured[:, i], matching.modelled[:, i], onset, window)
                  for i in signals]
        if states and all(s is not None for s in states) and any(states):
            frozen.append(component)
    # Two sensors frozen at once are no single part's fault.
    return frozen[0] if len(frozen) == 1 else None


def _frozen(measured: np.ndarray, modelled: np.ndarray, onset: int, window: int
            ) -> bool | None:
    """None: the reading did not freeze near ``onset``; else whether the model moves past
    it by `MODEL_MOVES_STEPS` of its steps before."""
    changed = np.flatnonzero(~(_steps(measured) == 0))   # NaNs count as changes
    since = int(changed[-1]) + 1 if changed.size else 0
    before, after = measured[:since], measured[since:]
    if not (abs(since - onset) <= window and len(after) >= window
            and before.size > window and np.isfinite(after[0])):
        return None
    steps = _steps(before[np.isfinite(before)])
    if (not (steps > 0).any() or LONGER_THAN_BEFORE * _longest_still(steps) >= len(after)
            or not np.nanmin(before) < after[0] < np.nanmax(before)):
        return None
    predicted = modelled[since:][np.isfinite(modelled[since:])]
    step = float(np.median(steps[steps > 0]))
    return bool(predicted.size) and float(np.ptp(predicted)) > MODEL_MOVES_STEPS * step


def _steps(values: np.ndarray) -> np.ndarray:
    """The size of each step of ``values``, 0 where it differs from the one before only in
    its last digits: a held reading resampled onto the model's grid by interpolation."""
    steps = np.abs(np.diff(values))
    return np.where(steps <= ROUNDING * np.abs(values[1:]), 0.0, steps)


def _longest_still(steps: np.ndarray) -> int:
    """The most steps in a row (of ``steps``, as `_steps` gives them) that read alike."""
    edges = np.concatenate([[-1], np.flatnonzero(steps > 0), [len(steps)]])
    return int(np.diff(edges).max()) - 1
