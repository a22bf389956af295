"""Where a change most likely began within a log, and how sure: shared by the change test
(a signal's residual against the log's own beginning) and the effort check (an actuator's
share of its group's effort against the log before a later start); and which way a
signal's residual moved from there."""

import math
from collections.abc import Sequence

import numpy as np

# The 95 % profile-likelihood interval of one change point: the starts whose statistic
# comes within this of the best one's, in z².
CHANGE_POINT_CHI2 = 3.84


def shift_start(values: np.ndarray, earliest: int, at: int) -> int:
    """Where, from step ``earliest`` to the detection at ``at``, the mean of ``values`` (one
    per step, NaN where unknown) most likely shifted: the step that maximises the squared
    sum of its departures from the mean before ``earliest``, over the steps after it (a
    GLR change point for a mean). A test that judges a run of windows dates a change to
    that run at best; the steps themselves date it within."""
    before = values[:earliest]
    before = before[np.isfinite(before)]
    if before.size < 2 or at <= earliest:
        return earliest
    departures = np.nan_to_num(values[earliest:at + 1] - before.mean(), nan=0.0)
    after = np.cumsum(departures[::-1])[::-1]          # sum from each step to ``at``
    steps = np.arange(after.size, 0, -1)
    return earliest + int(np.argmax(after * after / steps))


def held_over(running: np.ndarray, threshold: float, hold: int) -> int:
    """The first index from which ``running`` stays above ``threshold`` for ``hold`` steps
    (or to its end, where fewer are left); its last index where none does."""
    short = np.concatenate([[0], np.cumsum(running <= threshold)])   # steps not above, so far
    start = np.arange(len(running))
    held = np.flatnonzero(short[np.minimum(start + hold, len(running))] == short[start])
    return int(held[0]) if held.size else len(running) - 1


def likely_span(z: np.ndarray, start_times: np.ndarray, best: int, stride_s: float,
                seen_s: float, from_s: float | None = None) -> tuple[float, float]:
    """(earliest, latest): where a change point may lie, from a statistic ``z`` per start
    tried (at ``start_times``, ``best`` the largest): over the starts whose statistic comes
    within CHANGE_POINT_CHI2 of the best's, and on to the starts either side that fall
    short — the change lies between a start that falls short and the next that comes
    within, and where the starts are spaced in some other time than the log's (the steady
    time of the effort check), a gap between two is part of the span. Where the last start
    tried comes within, the change may lie after it, up to ``seen_s``, when it was seen:
    it began before that; where the first comes within, it may lie before it, back to
    ``from_s`` (the log's start: the first start tried has a span before it to judge
    against). A stride either side of the best at least."""
    floor = math.sqrt(max(float(z[best]) ** 2 - CHANGE_POINT_CHI2, 0.0))
    likely = np.flatnonzero(z >= floor)
    first, last = int(likely.min()), int(likely.max())
    at = float(start_times[best])
    earliest = float(start_times[first - 1]) if first > 0 else min(
        at - stride_s, at if from_s is None else from_s)
    latest = seen_s if last == len(z) - 1 else float(start_times[last + 1])
    return min(earliest, at - stride_s), min(max(latest, at + stride_s), max(seen_s, at))


def shift_ways(residual: np.ndarray, names: Sequence[str], flagged: Sequence[str],
               onset: int, at: int) -> dict[str, str]:
    """Which way each of ``flagged`` moved: its residual's mean from the onset to the alarm
    against its mean before the onset."""
    ways = {}
    for name in flagged:
        column = residual[:, list(names).index(name)]
        before, after = column[:onset], column[onset:at + 1]
        if np.isfinite(before).any() and np.isfinite(after).any():
            ways[name] = "above" if np.nanmean(after) > np.nanmean(before) else "below"
    return ways
