"""The chi-square distribution's lower quantiles (no SciPy here): how small a variance
estimate on a few degrees of freedom may come out by chance, so how large the true
variance may be behind one that came out small."""

import math

SERIES_TERMS = 500


def lower_tail(x: float, dof: float) -> float:
    """P(X ≤ x) for X ~ χ²(dof): the regularised lower incomplete gamma P(dof/2, x/2), by
    its power series (which converges for every x; the quantiles asked for here are small)."""
    if x <= 0:
        return 0.0
    a, half = dof / 2, x / 2
    term = total = 1.0 / a
    for n in range(1, SERIES_TERMS):
        term *= half / (a + n)
        total += term
        if term < total * 1e-15:
            break
    return min(1.0, math.exp(a * math.log(half) - half - math.lgamma(a)) * total)


def lower_quantile(p: float, dof: float) -> float:
    """The x with P(X ≤ x) = p, for 0 < p ≤ 0.5 (bisection)."""
    if not 0 < p <= 0.5 or dof <= 0:
        raise ValueError(f"lower_quantile needs 0 < p <= 0.5 and dof > 0, got p={p}, dof={dof}")
    low, high = 0.0, max(1.0, dof)
    for _ in range(100):
        middle = (low + high) / 2
        if lower_tail(middle, dof) < p:
            low = middle
        else:
            high = middle
    return (low + high) / 2


def largest_spread_factor(dof: float, confidence: float) -> float:
    """How many times an estimated spread on ``dof`` degrees of freedom the true spread may
    be, at ``confidence``: the upper confidence limit of σ is s·√(dof / χ²₁₋c(dof))."""
    return math.sqrt(dof / lower_quantile(1 - confidence, dof))
