"""The effort each actuator carries: its steady share of what the controller asks of the
actuators that act alike (the four rotors of a quadrotor, the horizontal thrusters of a
vectored ROV), learnt per vehicle from normal logs.

A controller holding attitude and depth drives a weak thruster or a damaged propeller
harder, so the fault shows in the commands' steady *level*, not in the motion and not in
their variation (mostly the controller reacting to noise). A healthy vehicle's shares are
not equal (centre of mass, trim, wear), so each is learnt, with its spread between normal
logs. Effort of actuator i at a step: |command_i| / |factor_i| (the frame's mixing factor:
the share it carries by design); the group's level is the mean effort; a span's share is
Σ effort_i / Σ level over its steady steps (the level weights the steps: a share at idle
means little). Steady: operating, and the level at least ``min_level``.

Noise model of a span's departure from normal (share − normal share): a between-log offset
(spread σ_b, measured between normal logs) plus within-log noise that averages out over the
span (σ_w for one window of W seconds, measured between a log's windows: the larger of
what windows of W and of LONG_WINDOW·W say, in the same units, so that a slow wander, which
windows shorter than it do not average out, is not taken for noise that does). For a span of T
seconds: σ(T)² = σ_b² + σ_w² · W · (1/T − 1/T_typ), where σ_b is measured on logs of the
typical steady time T_typ, each member's drawn towards the group's (`between_spread`; σ_w
likewise, `within_and_dof`). A new log's z = departure / (σ(T) √(1 + 1/n)) is Student-t
under normal operation, with the degrees of freedom of that estimate: (n − 1)(m − 1) for n
normal logs and m members (`drawn_towards_group`)."""

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from models.chi_square import largest_spread_factor

LEVEL_BINS = 3                # operating conditions of a one-way group (rotors): the level's
                              # terciles on normal logs; of a two-way group (a vectored ROV's
                              # thrusters): which of them push in reverse
MIN_LOGS = 3                  # normal logs needed to judge a group
MIN_WINDOWS = 2               # steady windows a log needs to be summarised or judged
CONDITIONED_GAIN = 0.9        # condition on the level only when it cuts the spread this much
MIN_BIN_LOGS = 2              # logs with steady time in a level bin for its own share
SPREAD_FLOOR = 0.002          # of a share: no spread is known better than this
LONG_WINDOW = 4               # windows this many times longer measure the slow wander
DEFAULT_FALSE_ALARM_RATE = 0.01   # per log
# Fewer normal logs than this are few: where they show no offset between them, their spread
# is taken at the upper limit of ALIKE_CONFIDENCE (`largest_spread_factor`); a log they
# judge near its threshold they cannot rule out (`effort_thresholds.Thresholds.near`).
ALIKE_CONFIDENCE = 0.95
FEW_LOGS = 5


@dataclass(frozen=True)
class EffortGroup:
    """Actuators that act alike on the vehicle (from the profile)."""

    name: str
    members: tuple[str, ...]          # command names
    factors: tuple[float, ...]        # |mixing factor| of each: the share it carries by design
    min_level: float | None = None    # steady from this level up; None: learnt
    window_s: float | None = None     # judging window; None: a sixth of a typical log
    # Projection on the mixer's reach where it misses directions of the group (from the
    # profile's controller; `models.effort_reach`), row by row; None: every direction.
    reach: tuple[tuple[float, ...], ...] | None = None
    # Row k: how the controller's balance of the tilting moments moves each member's effort
    # where member k falls short of what it is asked (its roll and pitch factors against
    # k's, from the profile's mix: a quadrotor's diagonal partner eased); None: not known.
    balance: tuple[tuple[float, ...], ...] | None = None
    driven_alone: bool = False        # a weak member driven harder alone (`shares_rule_out`)

    @property
    def projection(self) -> np.ndarray | None:
        return None if self.reach is None else np.asarray(self.reach, float)


def efforts(commands: np.ndarray, factors: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """(effort per step and actuator, the group's level per step) of the group's commands."""
    effort = np.abs(commands) / np.asarray(factors, float)
    return effort, effort.mean(axis=1)


@dataclass(frozen=True)
class GroupLog:
    """One log's steady effort in one group, as a model keeps it to refit from."""

    log: str
    steady_s: float
    effort: np.ndarray       # (bins, members): Σ effort over the steady steps of each level bin
    level: np.ndarray        # (bins,): Σ level
    within_var: np.ndarray   # (members,): variance of its windows' shares about its own
    windows: int
    # The same over windows LONG_WINDOW times as long (None: fewer than MIN_WINDOWS of them).
    long_var: np.ndarray | None = None
    long_windows: int = 0
    # (members, members): the covariance of its windows' shares (None: a model from before)
    within_cov: np.ndarray | None = None
    # The same log in its group's change bin alone (`effort_model.GroupSetup.change_bin`)
    change: "GroupLog | None" = None
    long_cov: np.ndarray | None = None      # the long windows' covariance (as within_cov)

    @property
    def share(self) -> np.ndarray:
        return self.effort.sum(axis=0) / self.level.sum()

    @property
    def identity(self) -> tuple[Any, ...]:
        """Equal for the same log summarised twice (names alone repeat across folders)."""
        return (self.log, round(self.steady_s, 3),
                tuple(np.round(self.effort.sum(axis=0), 4).tolist()))

    def to_json(self) -> dict[str, Any]:
        return {"log": self.log, "steady_s": round(self.steady_s, 3),
                "effort": self.effort.round(6).tolist(), "level": self.level.round(6).tolist(),
                "within_var": self.within_var.round(9).tolist(), "windows": self.windows,
                **({} if self.long_var is None else {
                    "long_var": self.long_var.round(9).tolist(),
                    "long_windows": self.long_windows}),
                **({} if self.within_cov is None else {
                    "within_cov": self.within_cov.round(9).tolist()}),
                **({} if self.change is None else {"change": self.change.to_json()}),
                **({} if self.long_cov is None else {
                    "long_cov": self.long_cov.round(9).tolist()})}

    @classmethod
    def from_json(cls, entry: dict[str, Any]) -> "GroupLog":
        return cls(str(entry["log"]), float(entry["steady_s"]), np.asarray(entry["effort"], float),
                   np.asarray(entry["level"], float), np.asarray(entry["within_var"], float),
                   int(entry["windows"]),
                   None if "long_var" not in entry else np.asarray(entry["long_var"], float),
                   int(entry.get("long_windows", 0)),
                   None if "within_cov" not in entry else np.asarray(entry["within_cov"], float),
                   None if "change" not in entry else cls.from_json(entry["change"]),
                   None if "long_cov" not in entry else np.asarray(entry["long_cov"], float))


def window_shares(effort: np.ndarray, level: np.ndarray, window_steps: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Shares over consecutive windows of ``window_steps`` steady steps (the last partial
    window dropped), and the index of each window's last step."""
    count = len(level) // window_steps
    used = count * window_steps
    sums = effort[:used].reshape(count, window_steps, -1).sum(axis=1)
    levels = level[:used].reshape(count, window_steps).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sums / levels[:, None], np.arange(count) * window_steps + window_steps - 1


def summarise(name: str, effort: np.ndarray, level: np.ndarray, bins: np.ndarray,
              n_bins: int, window_steps: int, dt_s: float) -> GroupLog | None:
    """A log's steady steps (already selected, each in its operating-condition bin) as a
    `GroupLog`; None when they make fewer than MIN_WINDOWS windows."""
    if len(level) < MIN_WINDOWS * window_steps or level.sum() <= 0:
        return None
    sums = np.zeros((n_bins, effort.shape[1]))
    np.add.at(sums, bins, effort)
    levels = np.bincount(bins, weights=level, minlength=n_bins)
    own = effort.sum(axis=0) / level.sum()

    def covariance(steps: int) -> tuple[np.ndarray, int]:
        shares, _ = window_shares(effort, level, steps)
        return (shares - own).T @ (shares - own) / max(1, len(shares) - 1), len(shares)

    within, windows = covariance(window_steps)
    summary = GroupLog(name, len(level) * dt_s, sums, levels, np.diag(within).copy(), windows,
                       within_cov=within)
    if len(level) < MIN_WINDOWS * LONG_WINDOW * window_steps:
        return summary
    long_cov, long_windows = covariance(LONG_WINDOW * window_steps)
    return replace(summary, long_var=np.diag(long_cov).copy(), long_windows=long_windows,
                   long_cov=long_cov)


def within_and_dof(logs: Sequence[GroupLog]) -> tuple[np.ndarray, float]:
    """(members,) σ_w of one window, pooled over the logs: the larger of what the windows
    and the long windows say (a long window's variance times LONG_WINDOW: how a span's
    noise would shrink with its length were the windows independent), each member's drawn
    towards the group's (`drawn_towards_group`: a window's shares average to one too); and
    the degrees of freedom it rests on: every log's windows (the
    long windows', fewer, where any log has them), times m - 1 for the members drawn
    together. Many more than the between-log spread's: a change within one log is judged
    on far firmer ground than a log against the others when the normal logs are few."""
    dof = sum(g.windows - 1 for g in logs)
    short = np.sum([g.within_var * (g.windows - 1) for g in logs], axis=0) / max(1, dof)
    long = [(g.long_var, g.long_windows - 1) for g in logs if g.long_var is not None]
    long_dof = sum(n for _, n in long)
    if not long_dof:
        variance, own_dof = short, float(max(1, dof))
    else:
        slow = LONG_WINDOW * np.sum([v * n for v, n in long], axis=0) / long_dof
        variance, own_dof = np.maximum(short, slow), float(long_dof)
    pooled, pooled_dof = drawn_towards_group(variance, own_dof)
    return np.asarray(np.sqrt(pooled)), pooled_dof


def _bin_means(logs: Sequence[GroupLog], conditioned: bool) -> np.ndarray:
    """(bins, members): the normal share in each level bin (every bin the pooled share when
    not conditioned, or where fewer than MIN_BIN_LOGS logs reach the bin)."""
    effort = np.sum([g.effort for g in logs], axis=0)
    level = np.sum([g.level for g in logs], axis=0)
    pooled = effort.sum(axis=0) / level.sum()
    means = np.tile(pooled, (len(level), 1))
    if conditioned:
        reached = np.sum([g.level > 0 for g in logs], axis=0)
        for b in np.flatnonzero(reached >= MIN_BIN_LOGS):
            means[b] = effort[b] / level[b]
    return means


def expected_share(means: np.ndarray, level: np.ndarray) -> np.ndarray:
    """The normal share of a span with this much level in each bin (its own mix of
    operating conditions)."""
    return np.asarray(level @ means / level.sum())


def _departures(logs: Sequence[GroupLog], conditioned: bool, leave_out: bool) -> np.ndarray:
    """(logs, members): each log's share minus the normal share, the normal share fitted on
    every log, or with ``leave_out`` on the others."""
    rows = []
    for i, log in enumerate(logs):
        fit = [g for j, g in enumerate(logs) if j != i] if leave_out else logs
        rows.append(log.share - expected_share(_bin_means(fit, conditioned), log.level))
    return np.array(rows)


@dataclass(frozen=True)
class GroupFit:
    """A group's normal effort, fitted from its normal logs."""

    group: EffortGroup
    min_level: float
    window_s: float
    conditioned: bool          # the share depends on the level (kept when it cut the spread)
    means: np.ndarray          # (bins, members)
    spread: np.ndarray         # (members,) σ_b: between logs, for a log of typical length
    within: np.ndarray         # (members,) σ_w: between one log's windows
    typical_s: float           # median steady time of a normal log
    logs: int
    dof: float                 # of the spread's estimate
    within_dof: float          # of σ_w's
    loo_z: np.ndarray          # (logs, members): each normal log judged by the others
    # The logs' shares differ no more than their own windows' noise says a log's share
    # would by chance: no offset between them shows (logs of one day or one battery, say).
    alike: bool = False
    # How many times its spread as seen the whole log is judged against (> 1: alike logs,
    # few of them: `FEW_LOGS`).
    widened: float = 1.0
    # (members, members): how its members' shares move together within a log
    # (`models.effort_correlation`; None: a model from before, which did not keep it)
    within_corr: np.ndarray | None = None
    # (members, members): the long windows' covariance times LONG_WINDOW, in units of σ_w:
    # a slow wander, along a direction where it exceeds the windows' noise
    within_slow: np.ndarray | None = None

    def sigma(self, span_s: float | np.ndarray) -> np.ndarray:
        """(…, members): σ(T) of a span of ``span_s`` steady seconds."""
        span = np.asarray(span_s, float)[..., None]
        extra = self.within ** 2 * self.window_s * (1 / span - 1 / self.typical_s)
        noise = np.maximum(self.spread ** 2 + extra, self.within ** 2 * self.window_s / span)
        return np.asarray(np.sqrt(np.maximum(noise, SPREAD_FLOOR ** 2))
                          * math.sqrt(1 + 1 / self.logs))


def fit_group(group: EffortGroup, logs: Sequence[GroupLog], min_level: float,
              window_s: float) -> GroupFit:
    """The normal shares (conditioned on the level where that validates better, leave one
    log out), their spreads, and each normal log's z judged by the others."""
    pooled = np.sqrt((_departures(logs, False, True) ** 2).mean())
    conditioned = bool(np.sqrt((_departures(logs, True, True) ** 2).mean())
                       <= CONDITIONED_GAIN * pooled)
    n = len(logs)
    within, within_dof = within_and_dof(logs)
    typical = float(np.median([g.steady_s for g in logs]))
    # With few logs, the windows inside them say how much a log's share wanders at least.
    floor = within * math.sqrt(window_s / typical)
    departures = _departures(logs, conditioned, False)
    spread, dof = between_spread(departures, floor)
    seen, _ = between_spread(departures, np.zeros_like(floor))
    alike = bool(np.sqrt(np.mean(seen ** 2)) <= np.sqrt(np.mean(floor ** 2)))
    # A handful of logs that show no offset between them are what one session gives: their
    # spread says only that it is small, and logs of another day carry offsets these never
    # sampled. Judge against the largest spread they do not rule out. Dozens that show none
    # show that the offsets are small.
    widened = largest_spread_factor(dof, ALIKE_CONFIDENCE) if alike and n < FEW_LOGS \
        else 1.0
    fit = GroupFit(group, min_level, window_s, conditioned, _bin_means(logs, conditioned),
                   spread * widened, within, typical, n, dof, within_dof,
                   np.zeros((n, len(group.members))), alike, widened)
    loo = []
    for i, log in enumerate(logs):
        others = [g for j, g in enumerate(logs) if j != i]
        rest = fit_group_fixed(fit, others)
        departure = log.share - expected_share(rest.means, log.level)
        loo.append(departure / rest.sigma(log.steady_s))
    return replace(fit, loo_z=np.array(loo))


def fit_group_fixed(fit: GroupFit, logs: Sequence[GroupLog]) -> GroupFit:
    """``fit`` refitted on other logs with its choices (conditioning, bins) kept."""
    typical = float(np.median([g.steady_s for g in logs]))
    spread, _ = between_spread(_departures(logs, fit.conditioned, False),
                               fit.within * math.sqrt(fit.window_s / typical))
    return replace(fit, means=_bin_means(logs, fit.conditioned), spread=spread,
                   typical_s=typical, logs=len(logs))


def between_spread(departures: np.ndarray, floor: np.ndarray, pool: bool = True
                   ) -> tuple[np.ndarray, float]:
    """Each member's spread between logs, from the logs' departures (logs, members), and the
    degrees of freedom of the estimate; never below ``floor``.

    One member's spread from n logs rests on n - 1 degrees of freedom: with three or four
    logs it is as likely to come out half as twice its true value, so a member that happened
    to vary little alarms on the next normal log, and one that varied much hides a fault.
    The members of a group share most of what changes between logs (battery, trim, payload,
    the air or water that day), so each member's variance is drawn towards the group's
    (`drawn_towards_group`). ``pool`` False: each member's own (the yardstick)."""
    own_dof = max(1, departures.shape[0] - 1)
    own = (departures ** 2).sum(axis=0) / own_dof
    if not pool:
        return np.maximum(np.sqrt(own), floor), float(own_dof)
    pooled, pooled_dof = drawn_towards_group(own, float(own_dof))
    return np.maximum(np.sqrt(pooled), floor), pooled_dof


def drawn_towards_group(own: np.ndarray, own_dof: float) -> tuple[np.ndarray, float]:
    """Each member's variance (``own``, each on ``own_dof`` degrees of freedom) drawn towards
    the group's, and the degrees of freedom of the result.

    A group's shares average to one, so of its m members' departures in a log (or a
    window) only m - 1 are free: their squares summed over the members and the logs rest
    on own_dof (m - 1) degrees of freedom, and divided by own_dof m they are each member's
    variance where the members share it (the mean of the members' own). Each member's own
    is 1/m of that evidence: (s_i^2 + (m - 1) s_g^2) / m, on own_dof (m - 1) degrees of
    freedom. Simulated departures (the same spread for every member) cross the Student-t
    threshold for those degrees of freedom at 0.95-1.2 times the rate it promises, for 2
    to 6 members and 3 to 15 logs; the group's sum of squares over its m - 1 free
    dimensions, claimed on own_dof m, crossed at 4.6 times it for a pair with three logs
    and at 0.6 times it for four members with seven."""
    members = len(own)
    if members < 2:
        return own, own_dof
    group = float(np.mean(own))
    return (own + (members - 1) * group) / members, own_dof * (members - 1)
