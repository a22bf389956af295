"""`calibrate --false-alarm-rate`: every judge's threshold from the distribution of its
statistic on the normal logs, the budget shared among the judges (`models.false_alarms`).

The judges are each judged signal's g in each mode with enough data (statistic: the log's
peak g), each sensor whose start is judged (the start's deviation from the normal start),
each actuator whose commands are judged against the motion (the log's peak extra effort),
each judged signal's change test (the log's largest window |z| and largest sum) and the
actuators of the effort groups (their own budget, `models.effort`). A normal log
alarms when any judge does: with k independent judges each gets 1 - (1 - R)^(1/k), k
counted from how the judges' statistics move together over the normal logs
(`models.false_alarms.effective_judges`). A start judge's law
is fitted to the training logs' starts as well as the calibration logs': the start is not
fitted by the model, so those are fair normal data, and more of them steady the law; so is
a change-test judge's, to the largest statistics of the logs trained on that the model
keeps (`jobs.training_change`). With
fewer calibration logs than a law of their peaks needs, a signal's g is judged from the
peaks of blocks of them (`Blocks`)."""

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.start_check import StartReading
from auvdiag_cli.numeric import peak
from auvdiag_errors import UsageError
from models.card import StartReference
from models.false_alarms import (
    MIN_LOGS,
    LawFit,
    checked_share,
    effective_judges,
    fit_law,
    judge_share,
)
from models.relation_forms import Relations

# With fewer calibration logs than a law over logs needs (`MIN_LOGS`), a g judge's law is
# fitted to the peaks of blocks of its logs, each this share of a log of the median length.
BLOCKS_PER_LOG = 6
RATE_PATTERN = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(/\s*h)?\s*$")


@dataclass(frozen=True)
class FalseAlarmBudget:
    """How often a normal log may alarm: ``rate`` per log, or per hour of operation."""

    rate: float
    per_hour: bool = False

    @classmethod
    def parse(cls, text: str) -> "FalseAlarmBudget":
        """'0.05' (a share of normal logs) or '0.5/h' (alarms per hour)."""
        found = RATE_PATTERN.match(text)
        if found is None:
            raise UsageError(f"--false-alarm-rate: expected a share of logs such as 0.05 or a "
                             f"rate per hour such as 0.5/h, got {text!r}")
        budget = cls(float(found.group(1)), found.group(2) is not None)
        if budget.rate <= 0 or (not budget.per_hour and budget.rate >= 0.5):
            raise UsageError("--false-alarm-rate must lie between 0 and 0.5 (a share of "
                             f"normal logs) or be a positive rate per hour, got {text!r}")
        return budget

    def per_log(self, log_hours: Sequence[float]) -> float:
        """The share of logs: per hour, for a log of the calibration logs' median length."""
        if not self.per_hour:
            return self.rate
        share = 1.0 - float(np.exp(-self.rate * float(np.median(log_hours))))
        if share >= 0.5:
            raise UsageError(f"--false-alarm-rate {self.rate:g}/h allows an alarm in most "
                             f"logs of {float(np.median(log_hours)):.2f} h: choose a lower rate")
        return share

    def describe(self) -> str:
        return (f"{self.rate:g} per hour" if self.per_hour
                else f"{self.rate:.3g} of normal logs ({self.rate:.1%})")


@dataclass(frozen=True)
class Blocks:
    """A judge's peak over each block of its calibration logs: two or three normal logs are
    too few for a law of their peaks, but their blocks are not. A log of the median length
    holds ``per_log`` blocks, so a log's share s of the budget is 1 - (1 - s)^(1/per_log)
    per block; blocks of one log are not quite independent (a slow disturbance spans
    them), which the law's predictive allowance for few values only partly covers."""

    peaks: tuple[float, ...]
    logs: tuple[int, ...]        # the calibration log of each block
    per_log: float

    def share(self, log_share: float) -> float:
        return 1.0 - (1.0 - log_share) ** (1.0 / self.per_log)


def blocks_of(series: Sequence[np.ndarray | None]) -> Blocks | None:
    """The peak over each block (BLOCKS_PER_LOG to a log of the median length; a last
    block under half that length left out) of each log's ``series`` (None: not in that
    log)."""
    lengths = [len(s) for s in series if s is not None and len(s)]
    if not lengths:
        return None
    steps = max(1, int(np.median(lengths)) // BLOCKS_PER_LOG)
    peaks, logs = [], []
    for log, values in enumerate(series):
        for start in range(0, 0 if values is None else len(values), steps):
            block = np.asarray(values)[start:start + steps]
            if 2 * len(block) >= steps and np.isfinite(highest := peak(block)):
                peaks.append(highest)
                logs.append(log)
    return Blocks(tuple(peaks), tuple(logs), float(np.median(lengths)) / steps)


@dataclass(frozen=True)
class Judge:
    """One judge and its statistic per calibration log (NaN: none in that log)."""

    kind: str                    # "g", "start", "command" or "change"
    name: str                    # the signal or the command
    mode: str | None             # g's mode
    values: tuple[float, ...]
    # The same statistic on other normal logs (the training logs' starts): they inform the
    # law, but are not among the calibration logs counted.
    more: tuple[float, ...] = ()
    # Its peaks over blocks of the logs, where the logs are too few for a law of their own.
    blocks: Blocks | None = None

    @property
    def label(self) -> str:
        return f"{self.kind} {self.name}" + (f" ({self.mode})" if self.mode else "")

    @property
    def statistic(self) -> np.ndarray:
        """What the threshold is compared with: |deviation| for a start, else the value."""
        values = np.asarray(self.values, float)
        return np.abs(values) if self.kind == "start" else values

    @property
    def law(self) -> str:
        return "student-t" if self.kind == "start" else "gumbel"

    def over(self, threshold: float) -> np.ndarray:
        """Which logs' statistics alarm at ``threshold``, as the diagnosis compares them: a
        start beyond it, the others (g, as the paper's b) from it on."""
        with np.errstate(invalid="ignore"):
            return np.asarray(self.statistic > threshold if self.kind == "start"
                              else self.statistic >= threshold)


@dataclass(frozen=True)
class JudgeFit:
    """A judge, its law, and its share of the budget after its own left-out logs."""

    judge: Judge
    fit: LawFit
    share: float
    offered: float               # what the budget offered it (per block for a block law)
    by_block: bool = False       # its law is of its logs' blocks (`Blocks`)

    @property
    def threshold(self) -> float:
        """The law's threshold, rounded up to the sixth decimal: rounding it down could put
        it below normal logs' values where they barely scatter (simulated dives that all
        start at rest alike)."""
        return math.ceil(self.fit.threshold(self.share) * 1e6) / 1e6

    @property
    def loo_alarms(self) -> int:
        return sum(self.fit.loo_alarms(self.share))


@dataclass(frozen=True)
class BudgetThresholds:
    budget: FalseAlarmBudget
    per_log_rate: float
    share: float                             # each judge's, by the budget
    fits: tuple[JudgeFit, ...]
    effort_rate: float | None                # the effort groups' budget (None: no groups)
    logs: int
    independent: float = 0.0                 # how many independent judges they amount to

    @property
    def lowered(self) -> tuple[JudgeFit, ...]:
        """The judges whose left-out logs alarmed more often than their law promised."""
        return tuple(f for f in self.fits if f.share < f.offered)

    def thresholds(self, kind: str) -> dict[tuple[str | None, str], float]:
        """(mode, name) -> threshold for one kind of judge."""
        return {(f.judge.mode, f.judge.name): f.threshold for f in self.fits
                if f.judge.kind == kind}

    def _flags(self, over: bool) -> np.ndarray:
        flags = np.zeros(self.logs, bool)
        for f in self.fits:
            if over:
                flags |= f.judge.over(f.threshold)
            elif f.by_block and f.judge.blocks is not None:   # a log alarms by any block
                np.logical_or.at(flags, list(f.judge.blocks.logs), f.fit.loo_alarms(f.share))
            else:
                flags |= np.asarray(f.fit.loo_alarms(f.share))[:self.logs]
        return flags

    @property
    def loo_logs_alarmed(self) -> int:
        """Logs that some judge, fitted on the other logs, flags."""
        return int(self._flags(over=False).sum())

    @property
    def in_sample_alarmed(self) -> int:
        """Logs over some judge's final threshold."""
        return int(self._flags(over=True).sum())

    def to_json(self) -> dict[str, Any]:
        return {"rate": self.budget.rate, "per": "hour" if self.budget.per_hour else "log",
                "per_log_rate": round(self.per_log_rate, 5), "share_per_judge":
                round(self.share, 5), "independent_judges": round(self.independent, 2),
                "effort_rate": self.effort_rate,
                "leave_one_log_out": {"logs": self.logs, "alarmed": self.loo_logs_alarmed},
                "calibration_logs_over_thresholds": self.in_sample_alarmed,
                "judges": [{"judge": f.judge.label, "threshold": f.threshold,
                            "law": f.fit.law, "logs": f.fit.logs, "by_block": f.by_block,
                            "share_after_leave_one_log_out": round(f.share, 5),
                            "loo_alarms": f.loo_alarms} for f in self.fits]}


def g_judges(per_log: Sequence[dict[str, np.ndarray]], modes: Sequence[str],
             judged: Sequence[str], sensor_names: Sequence[str]) -> list[Judge]:
    """Each judged signal's peak g per log in each mode (``per_log``: mode -> g, per log),
    and over blocks of the logs where they are too few for a law of their peaks."""
    judges = []
    for mode in modes:
        for name in judged:
            series = [g[mode][:, sensor_names.index(name)] if mode in g else None
                      for g in per_log]
            judges.append(Judge("g", name, mode, tuple(
                float("nan") if s is None else peak(s) for s in series),
                blocks=blocks_of(series) if len(per_log) < MIN_LOGS else None))
    return judges


def start_judges(start: StartReference, readings: Sequence[StartReading | None],
                 sensor_names: Sequence[str]) -> list[Judge]:
    """Each judged sensor's start deviation per log (NaN: not recorded from rest)."""
    if not start.usable:
        return []
    reference = np.asarray(start.reference, float)
    training = np.asarray(start.training_starts or np.empty((0, len(reference))), float)
    return [Judge("start", sensor_names[i], None, tuple(
        float("nan") if r is None else float(r.sensors[i] - reference[i]) for r in readings),
        tuple(float(v) for v in training[:, i] - reference[i] if np.isfinite(v)))
        for i, allowed in enumerate(start.thresholds) if allowed is not None]


def command_judges(relations: Relations | None, checks: Sequence[CommandCheck | None],
                   command_names: Sequence[str]) -> list[Judge]:
    """Each judged actuator's peak extra effort (or thrust lost) per log and window (NaN:
    not judged in that log; below zero: zero, for the check judges one way and a log whose
    actuator gave more than the relation expects all along came no nearer an alarm than
    one at zero, while a law fitted to such values spread past every positive peak: on
    five normal BlueROV2 missions a vertical thruster's allowed loss went to 97 %); a
    judge's mode is its window (None: the main one)."""
    judges: list[Judge] = []
    if relations is None:
        return judges
    for w, window in enumerate(relations.windows):
        mode = relations.window_label(w)
        for k, allowed in enumerate(window.thresholds.tolist()):
            if np.isnan(allowed):
                continue
            ratios = [None if c is None or len(c.peak_by_window) <= w
                      else c.peak_by_window[w].get(command_names[k]) for c in checks]
            judges.append(Judge("command", command_names[k], mode, tuple(
                float("nan") if r is None else max(r, 0.0) * allowed for r in ratios)))
    return judges


def with_command_thresholds(relations: Relations,
                            allowed: Mapping[tuple[str | None, str], float],
                            command_names: Sequence[str]) -> Relations:
    """The relations with the thresholds fitted to the budget (``allowed``: (mode, command)
    -> threshold, as `command_judges` names them; never below the least loss the relation
    judges, `least_judged`); the others kept."""
    windows = []
    for w, window in enumerate(relations.windows):
        extra = window.thresholds.copy()
        least = relations.least_judged(window.steps)
        for k, name in enumerate(command_names):
            fitted = allowed.get((relations.window_label(w), name))
            extra[k] = extra[k] if fitted is None else max(fitted, least)
        windows.append(extra)
    return relations.with_window_thresholds(windows)


def change_judges(peaks: Sequence[dict[str, dict[str, float]]], judged: Sequence[str],
                  trained: int = 0) -> list[Judge]:
    """Each judged signal's largest change-test statistic per log, a judge per statistic
    (its ``mode``; NaN: the log is too short); the last ``trained`` logs are logs the model
    was trained on, whose values inform the law beside the calibration logs' (`Judge.more`:
    the test judges each log against itself, which fitting the model to it does not
    shrink)."""
    statistics = sorted({statistic for p in peaks for statistic in p})
    calibration = len(peaks) - trained

    def values(statistic: str, name: str, logs: Sequence[dict[str, dict[str, float]]]
               ) -> tuple[float, ...]:
        return tuple(p.get(statistic, {}).get(name, float("nan")) for p in logs)

    judges = [Judge("change", name, statistic, values(statistic, name, peaks[:calibration]),
                    tuple(v for v in values(statistic, name, peaks[calibration:])
                          if math.isfinite(v)))
              for statistic in statistics for name in judged]
    # A judge no calibration log is long enough for gets no threshold and never alarms:
    # it takes no share of the budget from the others.
    return [j for j in judges if np.isfinite(j.values).any()]


def budget_thresholds(judges: Sequence[Judge], effort_actuators: int,
                      budget: FalseAlarmBudget, log_hours: Sequence[float]) -> BudgetThresholds:
    """Fit every judge that has enough logs (the others keep calibrate's rule, and count
    in the sharing all the same: they may alarm too). Each judge's share is checked on its
    own left-out logs: a heavy-tailed judge is held back without costing the others."""
    per_log = budget.per_log(log_hours)
    independent = effective_judges(np.array([judge.statistic for judge in judges])
                                   if judges else np.empty((0, 0)))
    share = judge_share(per_log, independent + effort_actuators)
    kept = tuple(fit for judge in judges if (fit := _judge_fit(judge, share)) is not None)
    effort_rate = (round(1.0 - (1.0 - share) ** effort_actuators, 6)
                   if effort_actuators else None)
    return BudgetThresholds(budget, per_log, share, kept, effort_rate, len(log_hours),
                            independent)


def refitted(fitted: BudgetThresholds, judges: Sequence[Judge]) -> BudgetThresholds:
    """The same judges measured otherwise (the change test with an input held), each given
    the share of the budget ``fitted`` gave each judge."""
    return replace(fitted, fits=tuple(fit for judge in judges
                                      if (fit := _judge_fit(judge, fitted.share)) is not None))


def _judge_fit(judge: Judge, share: float) -> JudgeFit | None:
    """The judge's law of its logs' statistics with its checked ``share``; with too few
    logs for that, the law of its logs' blocks with the share spread over a log's blocks;
    None where neither has enough values (calibrate's rule then stays)."""
    fit = fit_law([*judge.values, *judge.more], judge.law)
    if fit is not None:
        return JudgeFit(judge, fit, checked_share(fit, share), share)
    blocks = judge.blocks
    fit = None if blocks is None else fit_law(blocks.peaks, judge.law)
    if fit is None or blocks is None:
        return None
    offered = blocks.share(share)
    return JudgeFit(judge, fit, checked_share(fit, offered), offered, by_block=True)
