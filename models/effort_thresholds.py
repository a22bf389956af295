"""The effort check's thresholds: a false-alarm budget per log split over the judged
actuators and between the two tests (the whole log against the normal logs, and a change
within the log against its own beginning), each a Student-t quantile on the degrees of
freedom its spread rests on; and what a threshold means in a user's terms (the smallest
rise of one member's share it judges)."""

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from models.effort import FEW_LOGS, GroupFit
from models.effort_directions import judged_directions
from models.sign_test import median_lower_bound
from models.student_t import quantile

WHOLE_LOG_BUDGET = 0.8        # of the false-alarm budget: the whole log; the rest: later starts
# A whole log past the threshold this budget would set, where the model's is tighter and its
# normal logs few, is one they can neither clear nor convict (`Thresholds.near`).
NEAR_RATE = 0.05
# A log those logs cannot rule out is told how many normal logs like them would judge it,
# up to this many (past it, more than this).
MOST_LOGS_SAID = 100


@dataclass(frozen=True)
class Thresholds:
    """z thresholds for a false-alarm budget, and what leave-one-log-out said of them."""

    false_alarm_rate: float      # per log, the budget over every judged actuator
    actuators: int               # judged actuators (the budget's Bonferroni split)

    def whole_log(self, fit: GroupFit, dof: float | None = None, rate: float | None = None
                  ) -> float:
        """``dof``: were the spread known on that many degrees of freedom (None: its own);
        ``rate``: for this budget per log (None: the model's)."""
        budget = self.false_alarm_rate if rate is None else rate
        share = WHOLE_LOG_BUDGET * budget / self.actuators
        return widening(fit) * quantile(1 - share, fit.dof if dof is None else dof)

    def near(self, fit: GroupFit) -> float | None:
        """The whole-log threshold a budget of NEAR_RATE would set, where the model's budget
        is tighter and the group rests on fewer than FEW_LOGS normal logs; else None. Student's
        t on the few degrees of freedom such logs give sets a wide threshold (four logs of
        four rotors: 3.8 for 1 % a log, 2.8 for 5 %), and a log between the two is one they
        can neither clear nor convict: a simulated quadrotor's 20-25 mm cut, its rotor's
        share 10 % up, fell there in 22 of 80 logs, and 5 of 120 normal ones did (21 and 3
        of them matching the rotor's weakness clearly: `effort_naming.not_ruled_out`)."""
        if self.false_alarm_rate >= NEAR_RATE or fit.logs >= FEW_LOGS:
            return None
        return self.whole_log(fit, rate=NEAR_RATE)

    def later_start(self, fit: GroupFit, starts: int) -> float:
        """For the departure from one of ``starts`` later window starts to the end: a change
        against the log's own beginning, whose noise is the windows' (σ_w, on its own
        degrees of freedom; the between-log widening is not its to carry)."""
        share = (1 - WHOLE_LOG_BUDGET) * self.false_alarm_rate / (self.actuators
                                                                  * max(1, starts))
        return quantile(1 - share, fit.within_dof)


def widening(fit: GroupFit) -> float:
    """≥ 1: how much wider the group's normal logs, each judged by the others, scatter than
    t says (median |z| against t's quartile), where even its lower confidence bound passes
    the quartile (a handful of logs pass it by chance one time in three). Each group's own."""
    scatter, reference = np.abs(fit.loo_z).ravel(), quantile(0.75, max(1.0, fit.logs - 2))
    bound = median_lower_bound(scatter, fit.logs * max(1, len(fit.group.members) - 1))
    return 1.0 if bound is None or bound <= reference else float(np.nanmedian(scatter)) / reference


def smallest_rise(fit: GroupFit, thresholds: Thresholds, logs: int | None = None,
                  span_s: float | None = None, shares: np.ndarray | None = None
                  ) -> np.ndarray:
    """Per member, the smallest rise of its share (relative to its normal share: ``shares``,
    or the normal logs' mean) that the whole-log test judges over ``span_s`` steady seconds
    (None: the normal logs' typical steady time), the others' shares falling alike (one
    weak member). ``logs``: were the spread, as measured, known from that many normal logs
    (its degrees of freedom and the new log's share of the uncertainty in the normal shares
    scale with them): what more normal logs would buy. With three or four logs the Student-t
    threshold is wide; this says how wide in a user's terms (a motor's share 14 % up)."""
    n = fit.logs if logs is None else logs
    # The normal logs' scatter beyond t (`widening`) stays as measured on the logs there are.
    dof = fit.dof * max(1, n - 1) / max(1, fit.logs - 1)
    sigma = replace(fit, logs=n).sigma(fit.typical_s if span_s is None else span_s)
    return rise_judged(thresholds.whole_log(fit, dof), sigma,
                       fit.means.mean(axis=0) if shares is None else shares)


def logs_to_judge(fit: GroupFit, thresholds: Thresholds, ratio: float,
                  most: int = MOST_LOGS_SAID) -> int | None:
    """How many normal logs like the group's (their spread as measured) would judge a log
    whose whole-log statistic is ``ratio`` times the threshold its ``fit.logs`` set: with
    more of them the spread rests on more degrees of freedom and the new log's share of the
    uncertainty in the normal share shrinks (as `smallest_rise` counts them); None where
    fit.logs already do, or ``most`` would not."""
    if ratio > 1:
        return None
    z = ratio * thresholds.whole_log(fit)
    for logs in range(fit.logs + 1, most + 1):
        dof = fit.dof * (logs - 1) / max(1, fit.logs - 1)
        grown = z * math.sqrt((1 + 1 / fit.logs) / (1 + 1 / logs))
        if grown > thresholds.whole_log(fit, dof):
            return logs
    return None


def rise_judged(z_threshold: float, sigma: np.ndarray, shares: np.ndarray) -> np.ndarray:
    """Per member, the rise of its share (relative to ``shares``, its normal one) whose
    departure, the others' shares falling alike and each in units of its ``sigma``, projects
    on its weakness's direction to ``z_threshold``."""
    members = len(sigma)
    # Member i's share up by r, the others' down by r / (m - 1): its statistic is linear in r.
    pattern = (np.eye(members) * members - 1.0) / max(1, members - 1)
    per_unit = np.einsum("ij,ij->i", pattern / sigma, judged_directions(members))
    return np.asarray(z_threshold / per_unit / shares)


def thresholds_for(fits: Sequence[GroupFit], false_alarm_rate: float) -> Thresholds:
    """The budget split over the judged actuators of ``fits``; each group's whole-log
    threshold widened by its own normal logs' scatter (`widening`)."""
    return Thresholds(false_alarm_rate, sum(len(f.group.members) for f in fits))
