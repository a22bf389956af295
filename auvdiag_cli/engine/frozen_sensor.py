"""A sensor whose readings froze at the onset: every one of its signals reads one value from
then on, where before it changed at most steps, while the model of the healthy vehicle has
the motion it measures go on moving. No motion gives such a reading; a dead or stuck sensor
does. It names the sensor where no single-component fault explains the log: under a closed
loop the controller acts on the frozen reading, so the vehicle's motion changes too and the
replay of "that sensor dead" does not explain the rest (on the simulated BlueROV2 a dead
gyro left its heave at three times its threshold)."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.vehicle.profile import Sensor

# Before it froze, the reading changed at this share of its steps at least (a sensor that
# reads most steps alike, quantised or sampled slowly, is not judged).
MOVED_AT_LEAST = 0.5
# The model's motion after the onset spans this many of the reading's typical steps before:
# a vehicle at rest leaves a fine sensor reading one value as well.
MODEL_MOVES_STEPS = 10.0


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
    changed = np.flatnonzero(np.diff(measured) != 0)    # NaNs count as changes
    since = int(changed[-1]) + 1 if changed.size else 0
    before, after = measured[:since], measured[since:]
    if not (abs(since - onset) <= window and len(after) >= window
            and before.size > window and np.isfinite(after[0])):
        return None
    steps = np.abs(np.diff(before[np.isfinite(before)]))
    if (not steps.size or np.mean(steps > 0) < MOVED_AT_LEAST
            or not np.nanmin(before) < after[0] < np.nanmax(before)):
        return None
    predicted = modelled[since:][np.isfinite(modelled[since:])]
    step = float(np.median(steps[steps > 0]))
    return bool(predicted.size) and float(np.ptp(predicted)) > MODEL_MOVES_STEPS * step
