"""Diagnosis Part over time: alarms from b, the decided b vector, and the onset estimate."""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.vehicle.profile import PatternRow


@dataclass(frozen=True)
class Detection:
    alarm_index: int                 # first sample with any b_i = 1
    b: dict[str, int]                # b collected over the decision window after the alarm
    onset_index: int


def binary_vector(g_percent: np.ndarray, thresholds: np.ndarray) -> np.ndarray:
    """b_i(k) = 1 where g_i(k) ≥ t_i(k); NaN g (not enough data) never alarms."""
    with np.errstate(invalid="ignore"):
        return (g_percent >= thresholds).astype(np.int8)


def detect(b: np.ndarray, residual_fraction: np.ndarray, thresholds: np.ndarray,
           sensor_names: tuple[str, ...], decision_steps: int, lookback_steps: int,
           restarts: Sequence[int] = ()) -> Detection | None:
    """Find the first alarm; decide b over ``decision_steps`` after it; estimate the onset
    within ``lookback_steps`` before the alarm, and never before the replay's last restart
    (what came before it, e.g. time not operating, cannot hold the onset)."""
    alarm = first_alarm(b)
    if alarm is None:
        return None
    decided = decided_b(b, alarm, decision_steps)
    earliest = max([r for r in restarts if r <= alarm], default=0)
    window = min(lookback_steps, alarm - earliest)
    onsets = [
        _onset(residual_fraction[:, i], thresholds[alarm, i] / 100.0, alarm, window)
        for i in np.flatnonzero(decided)
    ]
    return Detection(alarm, {name: int(decided[i]) for i, name in enumerate(sensor_names)},
                     min(onsets))


def first_alarm(b: np.ndarray) -> int | None:
    alarms = np.flatnonzero(b.any(axis=1))
    return int(alarms[0]) if alarms.size else None


def decided_b(b: np.ndarray, alarm: int, decision_steps: int) -> np.ndarray:
    """b as read into the pattern table: every b_i that is 1 within the decision window
    after the first alarm (one residual may cross a little before another)."""
    return np.asarray(b[alarm:alarm + decision_steps + 1].any(axis=0))


def _onset(residual: np.ndarray, threshold: float, alarm: int, lookback_steps: int) -> int:
    """Where the residual began to depart: the CUSUM change point of |SS − SM| / R.

    With ν a quarter of the way from the residual's normal level to the threshold, the sum
    of (e − ν) falls while the vehicle is healthy and rises once the fault acts; its minimum
    before the alarm is the best single change time (Page's CUSUM estimate)."""
    lookback = max(0, alarm - lookback_steps)
    history = residual[lookback:alarm + 1]
    history = np.where(np.isfinite(history), history, 0.0)
    normal_level = float(np.median(history[: max(1, len(history) // 2)]))
    drift = normal_level + 0.25 * max(threshold - normal_level, 0.0)
    cusum = np.concatenate(([0.0], np.cumsum(history - drift)))
    return min(lookback + int(np.argmin(cusum)), alarm)   # the change is never after it


def look_up(pattern: tuple[PatternRow, ...], b: dict[str, int]) -> PatternRow | None:
    """The pattern-table row whose b vector equals ``b``, or None when no row fits."""
    return next((row for row in pattern if row.b == b), None)




def normal_case(pattern: tuple[PatternRow, ...], sensor_names: Sequence[str]) -> int | None:
    """The pattern table's case for no alarm (None: the table has no such row)."""
    row = look_up(pattern, {name: 0 for name in sensor_names})
    return None if row is None else row.case
