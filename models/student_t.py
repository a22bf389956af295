"""Student's t distribution: the quantiles the effort thresholds need (no SciPy here).

A threshold set from n normal logs must carry the uncertainty of their spread, which is
what t with n − 1 degrees of freedom does; the normal distribution would promise fewer
false alarms than a handful of logs can back."""

import math

import numpy as np

GRID_POINTS = 4001


def _log_density_constant(dof: float) -> float:
    return (math.lgamma((dof + 1) / 2) - math.lgamma(dof / 2)
            - 0.5 * math.log(dof * math.pi))


def upper_tail(x: float, dof: float) -> float:
    """P(T > x) for x ≥ 0 and dof ≥ 1, by Simpson's rule after the substitution
    t = √dof · tan θ, under which the density times dt is C √dof · cos^(dof − 1) θ dθ:
    smooth and bounded on the finite interval [atan(x / √dof), π/2]."""
    if x <= 0:
        return 0.5
    theta = np.linspace(math.atan(x / math.sqrt(dof)), math.pi / 2, GRID_POINTS)
    values = (np.exp(_log_density_constant(dof)) * math.sqrt(dof)
              * np.cos(theta) ** (dof - 1))
    h = (theta[-1] - theta[0]) / (GRID_POINTS - 1)
    weights = np.ones(GRID_POINTS)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    return float(h / 3 * (weights @ values))


def quantile(p: float, dof: float) -> float:
    """The x with P(T ≤ x) = p, for 0.5 ≤ p < 1 (bisection on the upper tail)."""
    if not 0.5 <= p < 1 or dof < 1:
        raise ValueError(f"quantile needs 0.5 <= p < 1 and dof >= 1, got p={p}, dof={dof}")
    tail = 1 - p
    low, high = 0.0, 1.0
    while upper_tail(high, dof) > tail:
        low, high = high, high * 2
    for _ in range(60):
        middle = (low + high) / 2
        if upper_tail(middle, dof) > tail:
            low = middle
        else:
            high = middle
    return (low + high) / 2
