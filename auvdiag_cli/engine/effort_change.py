"""A change of a group's shares within one log, judged from later starts against the log's
own span before each (`engine.effort_check`): over every steady step along the plain
signatures (a weak member's share up, the others' down alike), or, where the group's mixer
cannot drive it member by member, over the steps of its change bin along the mixer's
signatures, in the noise of its members moving together (`models.effort_correlation`)."""

from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.change_point import held_over
from auvdiag_cli.engine.effort_spans import (
    STARTS_PER_WINDOW,
    Spans,
    cumulative,
    date_change,
    later_starts,
)
from models.effort import GroupFit
from models.effort_correlation import unit_rows, whitening, with_slow_wander
from models.effort_directions import judged_directions
from models.effort_model import EffortLog, GroupSetup
from models.effort_reach import rises, signature_directions
from models.effort_thresholds import Thresholds

# A crossing counts as seen once it holds for this share of a stride: one that falls back
# sooner is the noise of the short spans just after a start, looked at end after end (taken
# for the detection, it saw a simulated rotor weakened in a flight's last 3 s 20 s before it
# weakened). Held for a whole stride, marginal true crossings of the simulated BlueROV2 were
# seen up to 12 s later.
HELD_SHARE_OF_STRIDE = 0.25


@dataclass(frozen=True)
class LogChange:
    spans: Spans
    times: np.ndarray          # of the steps judged
    window: int                # steps
    starts: list[int]
    threshold: float
    toward: np.ndarray         # (members, members): functionals of a change along each
    whiten: np.ndarray | None  # departures to coordinates of alike noise (None: plain)
    # (members, members): unit, in those coordinates (None: plain, as the whole log's)
    signatures: np.ndarray | None

    @property
    def steps(self) -> int:
        return int(self.spans.level_sum.shape[0] - 1)

    @property
    def stride(self) -> int:
        """Later starts every STARTS_PER_WINDOW-th of a window: the onset to that, not to
        a whole window."""
        return max(1, self.window // STARTS_PER_WINDOW)

    def ratios(self) -> np.ndarray:
        """(starts, members): each start's change to the end along each member's
        signature, over its threshold."""
        if not self.starts:
            return np.zeros((0, self.toward.shape[0]))
        changes = np.array([self.spans.changed(s, self.steps)[0] for s in self.starts])
        return np.asarray(changes @ self.toward.T / self.threshold)

    def seen(self, member: int, start: int) -> tuple[tuple[float, float], float, np.ndarray]:
        """After an alarm of ``member`` from the later start ``start``: (its onset and the
        error of it, when it was seen, the departures of the change from that start, in the
        coordinates its signatures are matched in). Seen: the first end, a stride on from
        the start and no sooner than it may have begun, from which the span's change stays
        past the threshold for a part of a stride (or to the log's end)."""
        n, stride = self.steps, self.stride
        onset_s, error_s = date_change(self.spans, self.toward[member], self.times,
                                       self.window, stride, n - 1)
        first = min(n, max(start + stride,
                           int(np.searchsorted(self.times, onset_s - error_s)) + 1))
        running = (self.spans.changed(start, np.arange(first, n + 1))
                   @ self.toward.T)[:, member]
        alarm = first + held_over(running, self.threshold,
                                  max(1, round(stride * HELD_SHARE_OF_STRIDE))) - 1
        onset = date_change(self.spans, self.toward[member], self.times, self.window, stride,
                            alarm)
        departure = self.spans.changed(start, n)[0]
        return onset, float(self.times[alarm]), (departure if self.whiten is None
                                                 else self.whiten @ departure)


def log_change(setup: GroupSetup, fit: GroupFit, change: GroupFit | None,
               thresholds: Thresholds, log: EffortLog, time_s: np.ndarray, dt_s: float
               ) -> LogChange:
    """The change test of ``log`` in one group: over its change bin where the model has its
    fit there (``change``), else over every steady step."""
    members = len(setup.group.members)
    change = setup.bin_fit(change)
    if change is None or setup.group.projection is None:
        steady, effort, level, bins = setup.steady_steps(log)
        spans = Spans(fit, *cumulative(effort, level, bins, setup.n_bins), dt_s)
        window = setup.window_steps(dt_s)
        starts = later_starts(len(level), window)
        return LogChange(spans, time_s[steady], window, starts,
                         thresholds.later_start(fit, len(starts)), judged_directions(members),
                         None, None)
    steady, effort, level = setup.change_steps(log)
    spans = Spans(change, *cumulative(effort, level, np.zeros(len(level), int), 1), dt_s)
    window = setup.change_window_steps(dt_s)
    starts = later_starts(len(level), window)
    commands = np.nan_to_num(log.group_commands(setup.group)[steady])
    share = effort.sum(axis=0) / level.sum() if level.sum() > 0 else np.ones(members)
    directions = signature_directions(
        rises(commands, np.asarray(setup.group.factors), setup.group.projection), share,
        change.within)
    whiten = with_slow_wander(whitening(change.within_corr, change.within), change.within_slow)
    signatures = unit_rows(directions @ whiten.T)
    toward = signatures @ whiten
    return LogChange(spans, time_s[steady], window, starts,
                     thresholds.later_start(change, len(starts)), toward, whiten, signatures)
