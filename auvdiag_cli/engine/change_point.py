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


# The blocks whose sums measure how much a gain's per-step evidence is worth
# (`gain_start`): its steps' errors are correlated, over times that the blocks' lengths
# probe; the most any length with enough blocks says is taken. On a simulated BlueROV2's
# thrust, blocks of 1, 2, 5 and 10 s said 2.2, 2.8, 3.4 and 6.8 times a white error's.
GAIN_BLOCKS_S = (1.0, 2.0, 5.0, 10.0, 20.0)
MIN_GAIN_BLOCKS = 4


def _gain_noise(numerator: np.ndarray, weight: np.ndarray, dt_s: float) -> float | None:
    """Per unit of weight, the variance of a span's sum of ``numerator`` (1 for white
    errors in units of their noise): the most that blocks of any of GAIN_BLOCKS_S with
    MIN_GAIN_BLOCKS or more say; None where no length has that many."""
    said = []
    for block_s in GAIN_BLOCKS_S:
        block = max(1, round(block_s / dt_s))
        count = len(numerator) // block
        sums = numerator[:count * block].reshape(count, block).sum(axis=1)
        weights = weight[:count * block].reshape(count, block).sum(axis=1)
        measured = weights > 0
        if measured.sum() >= MIN_GAIN_BLOCKS:
            said.append(float((sums[measured] ** 2).sum() / weights[measured].sum()))
    return max(1.0, *said) if said else None


def gain_start(numerator: np.ndarray, weight: np.ndarray, earliest: int, latest: int,
               at: int, dt_s: float) -> tuple[int, int, int] | None:
    """Where, from step ``earliest`` to ``latest``, a gain that is zero in normal operation
    (an actuator's share of thrust lost, its extra effort: over a span, the span's sum of
    ``numerator`` over its sum of ``weight``, per step) most likely became positive, judged
    up to ``at``: the start whose span to ``at`` gives the largest gain in units of its
    noise (a GLR change point), that noise measured before ``earliest`` (`_gain_noise`).
    (best, first, last): the best start and the likely ones either side
    (`CHANGE_POINT_CHI2`); None where too little comes before to measure the noise, or
    no start gives a gain."""
    noise = _gain_noise(numerator[:earliest], weight[:earliest], dt_s)
    if noise is None or at < latest or latest < earliest:
        return None
    span_num = np.cumsum(numerator[earliest:at + 1][::-1])[::-1][:latest - earliest + 1]
    span_weight = np.cumsum(weight[earliest:at + 1][::-1])[::-1][:latest - earliest + 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(span_weight > 0, span_num / np.sqrt(noise * span_weight), -np.inf)
    best = int(np.argmax(z))
    if not z[best] > 0:
        return None
    floor = math.sqrt(max(float(z[best]) ** 2 - CHANGE_POINT_CHI2, 0.0))
    likely = np.flatnonzero(z >= floor)
    return earliest + best, earliest + int(likely.min()), earliest + int(likely.max())


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
