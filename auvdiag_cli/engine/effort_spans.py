"""Spans of a log's steady steps judged by their share of a group's effort
(`engine.effort_check`): against the normal logs, or against the log's own span before a
later start. Running sums make every span's share a difference of two rows; and where, from
them, a change within the log began."""

from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.change_point import likely_span
from models.effort import SPREAD_FLOOR, GroupFit
from models.effort_model import EffortLog, GroupSetup
from models.effort_thresholds import Thresholds, rise_judged

STARTS_PER_WINDOW = 8
# Windows a later start needs after it to detect a change: the windows' noise is measured on
# whole windows, and a threshold for a shorter span would stretch that measure past what was
# measured. Dating a change already detected compares starts with one another, and tries
# shorter spans too (`date_change`).
WINDOWS_AFTER_START = 1


def cumulative(effort: np.ndarray, level: np.ndarray, bins: np.ndarray, n_bins: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """Running sums with a zero row in front: effort (steps+1, members) and level per bin
    (steps+1, bins)."""
    by_bin = np.zeros((len(level), n_bins))
    by_bin[np.arange(len(level)), bins] = level
    pad = lambda a: np.vstack([np.zeros((1, a.shape[1])), np.cumsum(a, axis=0)])  # noqa: E731
    return pad(effort), pad(by_bin)


@dataclass(frozen=True)
class Spans:
    """Departures of spans [start, end) of the steady steps, in units of their σ."""

    fit: GroupFit
    effort_sum: np.ndarray
    level_sum: np.ndarray
    dt_s: float

    def _departure(self, start: int, ends: np.ndarray) -> np.ndarray:
        """(ends, members): the share of [start, end) less its normal share."""
        effort = self.effort_sum[ends] - self.effort_sum[start]
        level = self.level_sum[ends] - self.level_sum[start]
        total = level.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.asarray((effort - level @ self.fit.means) / total[:, None])

    def z(self, start: int, end: np.ndarray | int) -> np.ndarray:
        """Against the normal logs: the span's departure in units of its σ."""
        ends = np.atleast_1d(end)
        return self._departure(start, ends) / self.fit.sigma((ends - start) * self.dt_s)

    def changed(self, start: int, end: np.ndarray | int) -> np.ndarray:
        """Against the log's own beginning: how far the departure of [start, end) lies from
        that of [0, start), in units of σ. The log's own offset from the normal logs (its
        battery, trim, payload) is in both and cancels; what is left is the windows' noise,
        σ_w √(W (1/T_after + 1/T_before))."""
        ends = np.atleast_1d(end)
        before = self._departure(0, np.array([start]))
        after_s = (ends - start) * self.dt_s
        return np.asarray((self._departure(start, ends) - before)
                          / change_spread(self.fit, after_s[:, None], start * self.dt_s))


def change_spread(fit: GroupFit, after_s: np.ndarray | float, before_s: float) -> np.ndarray:
    """σ of the difference between the shares of a span after a start and the span before
    it, in one log: the windows' noise alone, σ_w √(W (1/T_after + 1/T_before))."""
    return np.asarray(np.maximum(fit.within * np.sqrt(fit.window_s * (
        1 / np.asarray(after_s) + 1 / before_s)), SPREAD_FLOOR))


def date_change(spans: Spans, direction: np.ndarray, times: np.ndarray, window: int,
                stride: int, alarm: int) -> tuple[float, float]:
    """(onset_s, its error) of a change within the log, from the later starts on to the
    detection at steady step ``alarm``. Dating, unlike detecting, needs no window after a
    start: every stride from a window into the log up to the detection is tried (a short
    span's noise is the windows' scaled to its length), so a rotor lost in the log's last
    window is dated where it was lost, not at the last start detection tries, which the
    grid's statistic then peaked short of (`likely_span` gives the span of likely starts);
    then every step within a stride of the best start."""
    n = spans.level_sum.shape[0] - 1
    starts = np.arange(window, min(alarm, n - stride) + 1, stride)   # the first: a later start
    z = _changed_to_end(spans, starts, direction)
    best = int(np.argmax(z))
    earliest, latest = likely_span(z, times[starts], best, stride * spans.dt_s,
                                   float(times[alarm]), float(times[0]))
    error = max(stride * spans.dt_s, float(times[starts[best]]) - earliest,
                latest - float(times[starts[best]]))
    # Within a stride either side of the best start, every step: the grid dates a change
    # to a stride at best, the steps themselves date it within (the error stays the
    # grid's: the steps' own statistic, a step's noise apart, claims far more than it knows).
    steps = np.arange(max(window, int(starts[best]) - stride + 1),
                      min(int(starts[best]) + stride, alarm, n - 1) + 1)
    fine = _changed_to_end(spans, steps, direction)
    return float(times[steps[int(np.argmax(fine))]]), error


def _changed_to_end(spans: Spans, starts: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Per start, the change from there to the log's end, projected on ``direction``."""
    n = spans.level_sum.shape[0] - 1
    return np.asarray(np.array([spans.changed(int(s), n)[0] for s in starts]) @ direction)


def later_starts(steps: int, window: int) -> list[int]:
    """The later starts a log of ``steps`` steady steps is tried from (every
    STARTS_PER_WINDOW-th of a window, each with a window of the log before it and
    WINDOWS_AFTER_START after it)."""
    return list(range(window, steps - WINDOWS_AFTER_START * window + 1,
                      max(1, window // STARTS_PER_WINDOW)))


def typical_later_threshold(setup: GroupSetup, fit: GroupFit, thresholds: Thresholds,
                            dt_s: float, change: GroupFit | None = None) -> float:
    """The later-start test's threshold for a log of the normal logs' typical steady time
    (each log's own depends on its length: the number of starts it tries); over the change
    bin's steps and windows where the group has one (``change``, `GroupSetup.change_bin`)."""
    if (bin_fit := setup.bin_fit(change)) is not None:
        fit, window = bin_fit, setup.change_window_steps(dt_s)
    else:
        window = setup.window_steps(dt_s)
    return thresholds.later_start(fit, len(later_starts(round(fit.typical_s / dt_s), window)))


def smallest_later_rise(setup: GroupSetup, fit: GroupFit, thresholds: Thresholds,
                        dt_s: float) -> np.ndarray:
    """Per member, the smallest rise of its share that the later-start test judges when a
    weakness begins halfway through a log of the typical steady time: against the log's own
    first half, whose offset from the normal logs cancels, so far smaller than what the
    whole-log test needs with a handful of normal logs."""
    half_s = fit.typical_s / 2
    return rise_judged(typical_later_threshold(setup, fit, thresholds, dt_s),
                       change_spread(fit, half_s, half_s), fit.means.mean(axis=0))


def rise_since(setup: GroupSetup, log: EffortLog, time_s: np.ndarray, onset_s: float
               ) -> np.ndarray | None:
    """Per member, its share of the group's steady effort from ``onset_s`` on against its
    share before it, less one (None where either part holds no steady effort)."""
    steady, effort, level, _ = setup.steady_steps(log)
    at = int(np.searchsorted(time_s[steady], onset_s))
    before, after = level[:at].sum(), level[at:].sum()
    if not (before > 0 and after > 0):
        return None
    return np.asarray((effort[at:].sum(axis=0) / after) / (effort[:at].sum(axis=0) / before)
                      - 1.0)
