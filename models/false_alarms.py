"""Thresholds to a false-alarm budget, from one statistic per normal log.

A judge (one signal's g in one mode, one sensor's start, one actuator's extra effort)
alarms on a log when the log's statistic reaches its threshold. Given the statistic on
normal logs, the threshold is the quantile of a law fitted to them at 1 - the judge's share
of the budget, so that it extrapolates beyond the largest value seen:
- the peak of a series over a log (g, extra effort) is a maximum: a Gumbel law (maximum
  likelihood), the extreme-value law of maxima of light-tailed series;
- a reading taken once per log (where the log starts) is a level: a Student-t prediction
  interval around the normal logs' mean (two-sided: a zero may shift either way).
Every fit is checked by leave-one-log-out: each log's value against the law fitted on the
others gives its tail probability. Those say whether the law promises fewer alarms than
the logs show (a heavier tail than the law's): that judge's share is then lowered until
its left-out logs alarm no more often than its share allows.
"""

from collections.abc import Sequence
from dataclasses import dataclass

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


def judge_share(rate: float, judges: int) -> float:
    """Each of ``judges`` independent judges' share so that a normal log alarms on any of
    them at ``rate`` (Šidák)."""
    return float(1.0 - (1.0 - rate) ** (1.0 / max(1, judges)))


def gumbel_fit(maxima: np.ndarray) -> tuple[float, float]:
    """Location and scale of the Gumbel law of ``maxima`` by maximum likelihood (the scale
    solves β = mean - Σ x e^(-x/β) / Σ e^(-x/β); bisection on the standardised values)."""
    x = np.asarray(maxima, float)
    spread = float(x.std())
    if spread <= 0:
        return float(x.mean()), 0.0
    z = (x - x.mean()) / spread

    def excess(beta: float) -> float:
        w = np.exp(-(z - z.min()) / beta)      # at most 1: no overflow
        return float(beta - z.mean() + (z * w).sum() / w.sum())

    low, high = 1e-3, 10.0
    if excess(low) > 0 or excess(high) < 0:      # no root inside: the method of moments
        beta = np.sqrt(6.0) / np.pi
    else:
        for _ in range(60):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if excess(middle) < 0 else (low, middle)
        beta = 0.5 * (low + high)
    location = z.min() - beta * np.log(np.mean(np.exp(-(z - z.min()) / beta)))
    return float(x.mean() + spread * location), float(spread * beta)


def _fit(law: str, x: np.ndarray) -> tuple[float, ...]:
    if law == "gumbel":
        return gumbel_fit(x)
    return float(x.mean()), float(x.std(ddof=1) * np.sqrt(1.0 + 1.0 / len(x))), len(x) - 1.0


def _quantile(law: str, params: tuple[float, ...], share: float) -> float:
    if law == "gumbel":
        location, scale = params
        return location - scale * float(np.log(-np.log1p(-share)))
    mean, scale, dof = params
    return abs(mean) + quantile(1.0 - share / 2.0, dof) * scale


def _tail(law: str, params: tuple[float, ...], value: float) -> float:
    """The share at which ``value`` would just reach the threshold."""
    if law == "gumbel":
        location, scale = params
        if scale <= 0:
            return 1.0 if value <= location else 0.0
        return float(-np.expm1(-np.exp(-(value - location) / scale)))
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
