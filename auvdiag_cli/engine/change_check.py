"""A log judged against its own healthy beginning: a change test on the model's residuals.

The thresholds learnt across logs must allow for the scatter between logs (wind, payload,
trim, a model better on some logs than others). A failure that starts mid-log is seen
sooner against the same log's earlier residuals: at every step, each judged signal's
residual (measured less modelled) averaged over the last window is compared with the same
averages over everything the log showed before it (less one window, so that the change
itself does not enter its reference), in units of their spread there:

    z(t) = |mean of the last window - mean of the reference| / spread of the reference

It is judged once the reference holds `REFERENCE_MIN_S` of residuals. Its thresholds (one
per signal, on z) are set by `auvdiag calibrate` from the largest z of normal logs, like
the other judges; a model without them does not run the test. The change begins within the
window that first crosses: the onset is that window's start, give or take a window.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

REFERENCE_MIN_S = 30.0        # the log's own residuals needed before it is judged


@dataclass(frozen=True)
class ChangeCheck:
    """The change test on one log."""

    thresholds: Mapping[str, float]    # judged signal -> threshold on z
    peak_z: Mapping[str, float]        # judged signal -> its largest z in the log
    judged_from_s: float | None        # when the reference was long enough; None: never
    alarm_s: float | None = None       # the first step over a threshold
    onset_s: float | None = None       # the start of the window that crossed
    onset_error_s: float = 0.0         # give or take
    flagged: Mapping[str, float] = field(default_factory=dict)   # signal -> z / threshold

    @property
    def judged(self) -> bool:
        return self.judged_from_s is not None and bool(self.thresholds)

    def describe(self) -> str:
        if not self.judged:
            return (f"not judged (the log is too short: needs {REFERENCE_MIN_S:.0f} s of its "
                    "own residuals as its reference)")
        ratios = {n: self.peak_z[n] / t for n, t in self.thresholds.items()
                  if n in self.peak_z and t > 0}
        if self.alarm_s is None:
            worst = max(ratios, key=lambda n: ratios[n], default=None)
            return "no change against the log's own beginning" + (
                "" if worst is None else f" (largest: {worst} at {ratios[worst]:.0%} of its "
                                         "threshold)")
        which = ", ".join(f"{n} {r:.1f}x its threshold" for n, r in self.flagged.items())
        return (f"changed against the log's own beginning from ~{self.onset_s:.1f} s "
                f"(± {self.onset_error_s:.1f} s), detected at {self.alarm_s:.1f} s: {which}")


def _windowed_means(values: np.ndarray, window: int) -> np.ndarray:
    """Each step's mean over the last ``window`` steps (NaN where fewer than half are
    finite), per column."""
    finite = np.isfinite(values)
    sums = np.cumsum(np.where(finite, values, 0.0), axis=0)
    counts = np.cumsum(finite, axis=0)
    sums = np.vstack([np.zeros((1, values.shape[1])), sums])
    counts = np.vstack([np.zeros((1, values.shape[1]), int), counts])
    means = np.full(values.shape, np.nan)
    if values.shape[0] >= window:
        total = sums[window:] - sums[:-window]
        n = counts[window:] - counts[:-window]
        with np.errstate(invalid="ignore", divide="ignore"):
            means[window - 1:] = np.where(n * 2 >= window, total / np.maximum(n, 1), np.nan)
    return means


def change_statistic(residual: np.ndarray, window: int, reference_min: int) -> np.ndarray:
    """z per step and signal (NaN until the reference holds ``reference_min`` window
    means, and where the window has no mean)."""
    means = _windowed_means(residual, window)
    finite = np.isfinite(means)
    values = np.where(finite, means, 0.0)
    first = np.cumsum(values, axis=0)
    second = np.cumsum(values * values, axis=0)
    counts = np.cumsum(finite, axis=0)
    lag = window                         # the reference ends before the current window
    z = np.full(residual.shape, np.nan)
    if residual.shape[0] <= lag:
        return z
    n = counts[:-lag].astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = first[:-lag] / n
        spread = np.sqrt(np.maximum(second[:-lag] / n - mean * mean, 0.0))
        current = means[lag:]
        score = np.abs(current - mean) / spread
    score[(n < reference_min) | ~(spread > 0) | ~np.isfinite(current)] = np.nan
    z[lag:] = score
    return z


def change_peaks(residual: np.ndarray, names: Sequence[str], window: int, dt_s: float
                 ) -> dict[str, float]:
    """Each signal's largest z in a log (NaN where it is never judged): what calibrate
    sets the thresholds from."""
    z = change_statistic(residual, window, round(REFERENCE_MIN_S / dt_s))
    return {name: float(np.nanmax(z[:, i])) if np.isfinite(z[:, i]).any() else float("nan")
            for i, name in enumerate(names)}


def check_change(residual: np.ndarray, names: Sequence[str], thresholds: Mapping[str, float],
                 time_s: np.ndarray, window: int, dt_s: float) -> ChangeCheck:
    """The test on one log's residuals (columns ``names``), for the signals with a
    threshold."""
    judged = [i for i, name in enumerate(names) if name in thresholds]
    z = change_statistic(residual[:, judged], window, round(REFERENCE_MIN_S / dt_s))
    names_judged = [names[i] for i in judged]
    limits = np.array([thresholds[n] for n in names_judged])
    started = np.flatnonzero(np.isfinite(z).any(axis=1))
    peak_z = {n: round(float(np.nanmax(z[:, k])), 3) for k, n in enumerate(names_judged)
              if np.isfinite(z[:, k]).any()}
    check = ChangeCheck(dict(zip(names_judged, limits.tolist(), strict=True)), peak_z,
                        round(float(time_s[started[0]]), 3) if started.size else None)
    with np.errstate(invalid="ignore"):
        over = np.flatnonzero((z > limits).any(axis=1))
    if not over.size:
        return check
    at = int(over[0])
    flagged = {n: round(float(z[at, k] / limits[k]), 2) for k, n in enumerate(names_judged)
               if z[at, k] > limits[k]}
    return ChangeCheck(check.thresholds, peak_z, check.judged_from_s,
                       round(float(time_s[at]), 3),
                       round(float(time_s[max(at - window + 1, 0)]), 3), round(window * dt_s, 3),
                       dict(sorted(flagged.items(), key=lambda item: -item[1])))
