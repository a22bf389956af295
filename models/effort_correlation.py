"""How the members' shares of a group move together within a log, and the test of a change
along one member's signature that uses it.

The shares of a group move together: they average to one, and a vectored ROV's mixer ties
its thrusters in pairs (under way, forward and yaw move a thruster's share against its
fore-and-aft partner's, the other pair's alike). The normal logs' windows measure that
correlation R (members, members), on many more degrees of freedom than the between-log
spread (`models.effort.within_and_dof`). A change of a log's departures x (each member's in
units of its σ) along a member's signature h (unit, in the same units) is then judged by
the generalised likelihood ratio for a shift along h in noise of correlation R:

    z = hᵀ R⁺ x / √(hᵀ R⁺ h)

of unit variance under normal operation. Where R is only what the shares' averaging to one
makes it (every pair correlated −1/(m − 1)), z is the plain projection scaled by
√((m − 1)/m) (`models.effort_directions.judged_directions`); where the mixer ties members
together, the noise the ties carry is set aside and a weak thruster's signature stands out
of it (on the simulated BlueROV2: `benchmarks/effort.py`, docs/method.md). Where the mission
wanders slowly more than the windows say, the larger of the two is taken in each direction
of the noise (`with_slow_wander`)."""

from collections.abc import Sequence

import numpy as np

# R pooled from a few dozen windows is noisy in its small directions, where an inverse
# magnifies the noise: it is drawn towards the structure the averaging alone gives, by this
# many members' worth of windows against those it rests on (a shrinkage, as Ledoit and
# Wolf's, with a fixed weight).
SHRINK_WINDOWS_PER_MEMBER = 1.0


def pooled_covariance(covariances: Sequence[tuple[np.ndarray | None, int]]
                      ) -> np.ndarray | None:
    """The logs' (covariance, degrees of freedom) pooled; None where any lacks its
    covariance (a model from before) or none has a degree of freedom."""
    dof = sum(max(0, n) for _, n in covariances)
    if not covariances or dof < 1 or any(c is None for c, _ in covariances):
        return None
    return np.asarray(np.sum([np.asarray(c) * max(0, n) for c, n in covariances], axis=0) / dof)


def pooled_correlation(covariances: Sequence[tuple[np.ndarray | None, int]]
                       ) -> np.ndarray | None:
    """(members, members): the correlation of one window's shares within a log, pooled over
    the logs' (covariance, degrees of freedom), drawn towards the averaging's own; None where
    `pooled_covariance` is or the group has one member."""
    pooled = pooled_covariance(covariances)
    if pooled is None or pooled.shape[0] < 2:
        return None
    members = pooled.shape[0]
    spread = np.sqrt(np.maximum(np.diag(pooled), 1e-300))
    correlation = pooled / np.outer(spread, spread)
    dof = sum(max(0, n) for _, n in covariances)
    weight = min(1.0, SHRINK_WINDOWS_PER_MEMBER * members / dof)
    return np.asarray((1 - weight) * correlation + weight * averaging_correlation(members))


def averaging_correlation(members: int) -> np.ndarray:
    """The correlation shares that average to one have and nothing else: −1/(m − 1) between
    every two members."""
    off = -1.0 / max(1, members - 1)
    return np.asarray(np.full((members, members), off) + (1 - off) * np.eye(members))


def whitening(correlation: np.ndarray | None, sigma: np.ndarray) -> np.ndarray:
    """(members, members): T with T² = R⁺, taken across the constraint that departures in
    units of ``sigma`` obey (their shares average to one: Σ σ_j x_j = 0). T x is a
    departure in coordinates where the noise is alike in every direction, and T h a
    signature there. None: the averaging's correlation alone."""
    members = len(sigma)
    if correlation is None:
        correlation, sigma = averaging_correlation(members), np.ones(members)
    across = np.eye(members) - np.outer(sigma, sigma) / float(sigma @ sigma)
    values, vectors = np.linalg.eigh(across @ correlation @ across)
    kept = values > 1e-9 * max(float(values.max()), 1e-300)
    roots = np.where(kept, 1.0 / np.sqrt(np.where(kept, values, 1.0)), 0.0)
    return np.asarray((vectors * roots) @ vectors.T)


def with_slow_wander(whiten: np.ndarray, slow: np.ndarray | None) -> np.ndarray:
    """``whiten`` (`whitening`) taken further where the departures wander slowly more than
    the windows' noise says (``slow``: the covariance of long windows' departures, in a
    window's terms; a mission's legs, each trimmed its own way): every direction judged
    against the larger of the two, max(I, T S T), so that a change's size along each
    signature and its likeness to each are read in the same noise."""
    if slow is None:
        return whiten
    values, vectors = np.linalg.eigh(whiten @ slow @ whiten)
    return np.asarray((vectors / np.sqrt(np.maximum(values, 1.0))) @ vectors.T @ whiten)


def unit_rows(rows: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(rows, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(np.where(norms > 0, rows / norms, 0.0))

