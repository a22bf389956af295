"""Thresholds to a false-alarm budget, from one statistic per normal log.

A judge (one signal's g in one mode, one sensor's start, one actuator's extra effort)
alarms on a log when the log's statistic reaches its threshold. Given the statistic on
normal logs, the threshold is the quantile of a law fitted to them at 1 - the judge's share
of the budget, so that it extrapolates beyond the largest value seen:
- the peak of a series over a log (g, extra effort) is a maximum: a Gumbel law (maximum
  likelihood), the extreme-value law of maxima of light-tailed series; its threshold is
  predictive: it allows for the scatter of a fit to that many logs (found once per count
  of logs by simulation: the law is location-scale, so that scatter is the same for any);
- a reading taken once per log (where the log starts) is a level: a Student-t prediction
  interval around the normal logs' mean (two-sided: a zero may shift either way).
Every fit is checked by leave-one-log-out: each log's value against the law fitted on the
others gives its tail probability. Those say whether the law promises fewer alarms than
the logs show (a heavier tail than the law's): that judge's share is then lowered until
its left-out logs alarm no more often than its share allows.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from models.student_t import quantile, upper_tail

MIN_LOGS = 5                 # fewer normal logs and no law is fitted
LAWS = ("gumbel", "student-t")


@dataclass(frozen=True)
class LawFit:
    """A law fitted to one judge's normal values, and each value's tail probability under
    the law fitted without it."""

    law: str
    params: tuple[float, ...]
    loo_tail: tuple[float, ...]      # per value given; NaN where the value was missing

    @property
    def logs(self) -> int:
        return int(np.isfinite(self.loo_tail).sum())

    def threshold(self, share: float) -> float:
        return _quantile(self.law, self.params, share)

    def loo_alarms(self, share: float) -> tuple[bool, ...]:
        with np.errstate(invalid="ignore"):
            return tuple(bool(p <= share) for p in self.loo_tail)


def judge_share(rate: float, judges: float) -> float:
    """Each of ``judges`` independent judges' share so that a normal log alarms on any of
    them at ``rate`` (Šidák)."""
    return float(1.0 - (1.0 - rate) ** (1.0 / max(1.0, judges)))


def effective_judges(values: np.ndarray) -> float:
    """How many independent judges the judges with these statistics (judges x normal logs)
    amount to.

    Judges of one vehicle are not independent (a gust moves the roll, its rate and the
    yaw together), and sharing the budget as if they were sets every threshold higher than
    the budget needs. The count is Li and Ji's (Heredity 95, 2005): from the eigenvalues
    of the judges' correlation over the logs, each counts one for being at least one and
    its fraction besides (a group of judges that move as one counts about one). The
    correlation is of ranks, so that one log far out (a disturbance) does not make judges
    look alike; logs missing a judge's value are left out. At least one, at most the
    number of judges; all of them where fewer than MIN_LOGS logs have every value."""
    statistics = np.atleast_2d(np.asarray(values, float))
    judges = len(values)
    complete = statistics[:, np.isfinite(statistics).all(axis=0)]
    if judges < 2 or complete.shape[1] < MIN_LOGS:
        return float(judges)
    ranks = complete.argsort(axis=1).argsort(axis=1).astype(float)
    varied = ranks.std(axis=1) > 0
    if varied.sum() < 2:
        return float(judges)
    with np.errstate(invalid="ignore"):
        eigenvalues = np.linalg.eigvalsh(np.corrcoef(ranks[varied]))
    count = float(np.sum((eigenvalues >= 1.0) + (eigenvalues - np.floor(eigenvalues))
                         * (eigenvalues > 0)))
    # n logs show at most n - 1 directions: judges beyond those count as independent.
    unseen = max(0, int(varied.sum()) - (complete.shape[1] - 1))
    return float(np.clip(count + unseen + judges - varied.sum(), 1.0, judges))


def gumbel_fit(maxima: np.ndarray) -> tuple[float, float]:
    """Location and scale of the Gumbel law of ``maxima`` by maximum likelihood."""
    location, scale = _gumbel_fits(np.asarray(maxima, float)[None, :])
    return float(location[0]), float(scale[0])


def _gumbel_fits(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Maximum-likelihood location and scale of each row of ``samples``: the scale solves
    β = mean - Σ x e^(-x/β) / Σ e^(-x/β), by bisection on the standardised values; a row
    without a root inside the bracket takes the method of moments."""
    x = np.asarray(samples, float)
    mean, spread = x.mean(axis=1, keepdims=True), x.std(axis=1, keepdims=True)
    flat = spread[:, 0] <= 0
    z = (x - mean) / np.where(spread > 0, spread, 1.0)
    low_z = z.min(axis=1, keepdims=True)

    def excess(beta: np.ndarray) -> np.ndarray:
        w = np.exp(-(z - low_z) / beta[:, None])      # at most 1: no overflow
        return np.asarray(beta - z.mean(axis=1) + (z * w).sum(axis=1) / w.sum(axis=1))

    rows = len(x)
    low, high = np.full(rows, 1e-3), np.full(rows, 10.0)
    bracketed = (excess(low) <= 0) & (excess(high) >= 0)
    for _ in range(60):
        middle = 0.5 * (low + high)
        below = excess(middle) < 0
        low, high = np.where(below, middle, low), np.where(below, high, middle)
    beta = np.where(bracketed, 0.5 * (low + high), np.sqrt(6.0) / np.pi)
    location = low_z[:, 0] - beta * np.log(np.mean(np.exp(-(z - low_z) / beta[:, None]),
                                                   axis=1))
    return (np.where(flat, mean[:, 0], mean[:, 0] + spread[:, 0] * location),
            np.where(flat, 0.0, spread[:, 0] * beta))


PREDICTIVE_DRAWS = 2000      # standard Gumbel samples behind a predictive threshold


@lru_cache(maxsize=32)
def _gumbel_pivots(logs: int) -> tuple[np.ndarray, np.ndarray]:
    """The fitted location and scale of PREDICTIVE_DRAWS standard Gumbel samples of
    ``logs`` values: how a fit to that many logs scatters about its law. The Gumbel is a
    location-scale law, so (x - location) / scale of a new maximum has one distribution
    whatever the true law, and these give it."""
    draws = np.random.default_rng(0).gumbel(size=(PREDICTIVE_DRAWS, logs))
    return _gumbel_fits(draws)


def _gumbel_tail(standardised: float, logs: int) -> float:
    """The chance that a new maximum lies beyond location + ``standardised`` x scale of a
    fit to ``logs`` maxima, the fit's own uncertainty included (a prediction, as the
    Student-t interval is for levels)."""
    location, scale = _gumbel_pivots(logs)
    return float(np.mean(-np.expm1(-np.exp(-(location + standardised * scale)))))


def _gumbel_quantile(share: float, logs: int) -> float:
    """The standardised threshold whose predictive tail is ``share`` (bisection)."""
    low, high = -10.0, 10.0
    while _gumbel_tail(high, logs) > share:
        high *= 2.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _gumbel_tail(middle, logs) > share else (low, middle)
    return 0.5 * (low + high)


def _fit(law: str, x: np.ndarray) -> tuple[float, ...]:
    if law == "gumbel":
        return (*gumbel_fit(x), float(len(x)))
    return float(x.mean()), float(x.std(ddof=1) * np.sqrt(1.0 + 1.0 / len(x))), len(x) - 1.0


def _quantile(law: str, params: tuple[float, ...], share: float) -> float:
    if law == "gumbel":
        location, scale, logs = params
        return location + scale * _gumbel_quantile(share, int(logs))
    mean, scale, dof = params
    return abs(mean) + quantile(1.0 - share / 2.0, dof) * scale


def _tail(law: str, params: tuple[float, ...], value: float) -> float:
    """The share at which ``value`` would just reach the threshold."""
    if law == "gumbel":
        location, scale, logs = params
        if scale <= 0:
            return 1.0 if value <= location else 0.0
        return _gumbel_tail((value - location) / scale, int(logs))
    mean, scale, dof = params
    excess = abs(value) - abs(mean)
    if excess <= 0:
        return 1.0
    return 0.0 if scale <= 0 else min(1.0, 2.0 * upper_tail(excess / scale, dof))


def fit_law(values: Sequence[float], law: str) -> LawFit | None:
    """``law`` fitted to the finite ``values`` ("gumbel": per-log peaks; "student-t":
    per-log levels, compared as |level|), or None below MIN_LOGS of them."""
    if law not in LAWS:
        raise ValueError(f"unknown law {law!r}")
    given = np.asarray(values, float)
    present = np.flatnonzero(np.isfinite(given))
    x = given[present]
    if len(x) < MIN_LOGS:
        return None
    tails = np.full(len(given), np.nan)
    for j, i in enumerate(present):
        tails[i] = _tail(law, _fit(law, np.delete(x, j)), float(x[j]))
    return LawFit(law, _fit(law, x), tuple(float(t) for t in tails))


def checked_share(fit: LawFit, share: float) -> float:
    """``share``, lowered where the judge's left-out logs alarm more often than it allows
    (more than round(share x logs) of them): then just below the tail probability of the
    first left-out value past that count."""
    tails = np.sort(np.asarray(fit.loo_tail)[np.isfinite(fit.loo_tail)])
    allowed = round(share * len(tails))
    if len(tails) <= allowed or tails[allowed] > share:
        return share
    return float(np.nextafter(tails[allowed], 0.0))
