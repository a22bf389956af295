"""A lower confidence bound for a median that assumes no distribution (the sign test): of
n independent values, the number below the true median is Binomial(n, 1/2), so the k-th
smallest lies below it with a probability the binomial gives. With a handful of normal logs
their median |z| wanders far by chance; the bound says how high it is at least."""

import math

import numpy as np

DEFAULT_CONFIDENCE = 0.9


def lower_rank(free: int, confidence: float = DEFAULT_CONFIDENCE) -> int:
    """The largest k (1-based) such that the k-th smallest of ``free`` independent values
    lies at or below their true median with at least ``confidence``; 0 where even the
    smallest does not (too few values to bound the median at all)."""
    below = 0.0         # P(fewer than k of the values fall below the median)
    rank = 0
    for k in range(1, free + 1):
        below += math.comb(free, k - 1) / 2 ** free
        if below > 1 - confidence:
            break
        rank = k
    return rank


def median_lower_bound(values: np.ndarray, free: int,
                       confidence: float = DEFAULT_CONFIDENCE) -> float | None:
    """A value the true median of ``values`` exceeds with ``confidence``: the order statistic
    of `lower_rank` among ``free`` independent values, read at the same fraction of
    ``values`` (more of them than are free where they are tied, as shares that average to
    one are); values that are not finite say nothing. None: too few free values to bound
    it."""
    rank = lower_rank(free, confidence)
    finite = np.asarray(values, float)[np.isfinite(values)]
    if rank == 0 or not len(finite):
        return None
    return float(np.quantile(finite, (rank - 1) / max(1, free - 1)))
