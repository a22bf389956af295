"""A vehicle's normal effort model: every group's fit from normal logs, the thresholds for
a false-alarm budget, and the per-log summaries it was fitted from (so that `calibrate`
can add normal logs and refit, and the model file says what it rests on). Stored in
model.json as the ``effort`` entry; the fit is recomputed from the summaries at load, so
the numbers a report shows and the ones that judged can never drift apart."""

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from models.effort import (
    DEFAULT_FALSE_ALARM_RATE,
    LEVEL_BINS,
    LONG_WINDOW,
    MIN_LOGS,
    MIN_WINDOWS,
    SPREAD_FLOOR,
    EffortGroup,
    GroupFit,
    GroupLog,
    efforts,
    fit_group,
    summarise,
)
from models.effort_correlation import pooled_correlation, pooled_covariance
from models.effort_reach import as_table
from models.effort_thresholds import Thresholds, smallest_rise, thresholds_for

FORMAT_VERSION = 1
MIN_WINDOW_S, MAX_WINDOW_S = 2.0, 30.0
WINDOWS_PER_LOG = 6           # the window: this fraction of a typical log's steady time
IDLE_LEVEL = 1e-3             # a level this low is an actuator at rest, not operating
LEARNT_MIN_LEVEL = 0.5        # of the median operating level: steady from there up
# A change bin (`GroupSetup.change_bin`) holds at least this share of the normal logs'
# steady effort; its windows are this many to a judging window: its noise, measured on
# them, on more degrees of freedom (the simulated BlueROV2's windows of 5 s against 16 s).
MIN_CHANGE_SHARE = 0.5
CHANGE_WINDOWS_PER_WINDOW = 3


@dataclass(frozen=True)
class EffortLog:
    """One log's actuator signals (commands, outputs) on the model grid, and the steps that
    may be judged."""

    name: str
    commands: np.ndarray          # (steps, n_commands)
    usable: np.ndarray            # (steps,) operating, not a DMS run
    command_names: tuple[str, ...]

    def group_commands(self, group: EffortGroup) -> np.ndarray:
        return self.group_commands_of(group.members)

    def group_commands_of(self, members: Sequence[str]) -> np.ndarray:
        columns = [self.command_names.index(name) for name in members]
        return self.commands[:, columns]

    def group_efforts(self, group: EffortGroup) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(effort, level, usable) of the group's actuators; NaN commands are not usable."""
        selected = self.group_commands(group)
        effort, level = efforts(np.nan_to_num(selected), group.factors)
        return effort, level, self.usable & np.isfinite(selected).all(axis=1)


@dataclass(frozen=True)
class GroupSetup:
    """What a group's fit fixes before fitting: the steady level, bins and window."""

    group: EffortGroup
    min_level: float
    edges: np.ndarray        # level terciles (a one-way group's conditions)
    window_s: float
    two_way: bool            # some actuator pushed in reverse on normal logs
    # Where the mixer cannot drive the group member by member (a vectored ROV), a weak
    # member's signature depends on which way each pushes: a change within a log is judged
    # in the operating condition (bin) that holds most of the normal logs' steady effort,
    # where the signature is fixed, over windows of ``change_window_s`` (None: every steady
    # step, along the plain signatures).
    change_bin: int | None = None
    change_window_s: float = 0.0

    @property
    def n_bins(self) -> int:
        return 2 ** len(self.group.members) if self.two_way else len(self.edges) + 1

    def bins(self, commands: np.ndarray, level: np.ndarray) -> np.ndarray:
        """Each step's operating condition: for a two-way group the pattern of actuators
        pushing in reverse (forward, turning, backing off load them differently), else the
        level's tercile (hover, climb)."""
        if self.two_way:
            return np.asarray((commands < 0) @ (1 << np.arange(commands.shape[1])), int)
        return np.digitize(level, self.edges)

    def steady(self, level: np.ndarray, usable: np.ndarray) -> np.ndarray:
        return usable & (level >= self.min_level)

    def steady_steps(self, log: EffortLog) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray]:
        """(indices, effort, level, condition bin) of the log's steady steps."""
        effort, level, usable = log.group_efforts(self.group)
        steady = np.flatnonzero(self.steady(level, usable))
        commands = np.nan_to_num(log.group_commands(self.group)[steady])
        return steady, effort[steady], level[steady], self.bins(commands, level[steady])

    def summarise(self, log: EffortLog, dt_s: float) -> GroupLog | None:
        _, effort, level, bins = self.steady_steps(log)
        summary = summarise(log.name, effort, level, bins, self.n_bins,
                            self.window_steps(dt_s), dt_s)
        if summary is None or self.change_bin is None:
            return summary
        inside = bins == self.change_bin
        return replace(summary, change=summarise(
            log.name, effort[inside], level[inside], np.zeros(int(inside.sum()), int), 1,
            self.change_window_steps(dt_s), dt_s))

    def change_steps(self, log: EffortLog) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(indices, effort, level) of the log's steady steps in the change bin."""
        steady, effort, level, bins = self.steady_steps(log)
        inside = bins == self.change_bin
        return steady[inside], effort[inside], level[inside]

    def bin_fit(self, change: GroupFit | None) -> GroupFit | None:
        """``change``, the fit of its change bin, where it has one; None: its change test
        judges every steady step along the plain signatures."""
        return change if self.change_bin is not None else None

    def change_window_steps(self, dt_s: float) -> int:
        return max(1, round(self.change_window_s / dt_s))

    def window_steps(self, dt_s: float) -> int:
        return max(1, round(self.window_s / dt_s))

    def needs_s(self) -> float:
        return MIN_WINDOWS * self.window_s


@dataclass(frozen=True)
class EffortModel:
    dt_s: float
    false_alarm_rate: float
    setups: tuple[GroupSetup, ...]
    summaries: tuple[tuple[GroupLog, ...], ...]    # per setup
    fits: tuple[GroupFit | None, ...]              # None: too few logs to judge the group
    refused: tuple[str | None, ...]                # per setup: why it is not judged
    thresholds: Thresholds | None
    # Per setup, the fit of its change bin's windows (`change_fit`; None: no change bin)
    change_fits: tuple[GroupFit | None, ...] = ()

    @classmethod
    def fitted(cls, setups: Sequence[GroupSetup], summaries: Sequence[Sequence[GroupLog]],
               dt_s: float, false_alarm_rate: float) -> "EffortModel":
        fits: list[GroupFit | None] = []
        refused: list[str | None] = []
        for setup, logs in zip(setups, summaries, strict=True):
            if len(logs) < MIN_LOGS:
                fits.append(None)
                refused.append(
                    f"not judged (needs {MIN_LOGS} normal logs with {setup.needs_s():.0f} s "
                    f"of steady effort each, at least {setup.min_level:.3g} of full scale; "
                    f"had {len(logs)})")
                continue
            fits.append(fit_group(setup.group, logs, setup.min_level, setup.window_s))
            refused.append(None)
        judged = [f for f in fits if f is not None]
        return cls(dt_s, false_alarm_rate, tuple(setups), tuple(tuple(s) for s in summaries),
                   tuple(fits), tuple(refused),
                   thresholds_for(judged, false_alarm_rate) if judged else None,
                   tuple(None if fit is None else change_fit(fit, setup, logs)
                         for setup, logs, fit in zip(setups, summaries, fits, strict=True)))

    @property
    def judges_anything(self) -> bool:
        return self.thresholds is not None

    def with_logs(self, logs: Sequence[EffortLog], false_alarm_rate: float | None
                  ) -> tuple["EffortModel", list[str]]:
        """This model refitted with more normal logs (each summarised with the model's own
        levels, bins and windows), and what was left out."""
        notes: list[str] = []
        summaries = []
        for setup, kept in zip(self.setups, self.summaries, strict=True):
            known = {g.identity for g in kept}
            added = list(kept)
            for log in logs:
                summary = setup.summarise(log, self.dt_s)
                if summary is None:
                    notes.append(f"{log.name}: too little steady effort in {setup.group.name} "
                                 f"(needs {setup.needs_s():.0f} s)")
                elif summary.identity in known:
                    notes.append(f"{log.name}: already among the model's normal logs")
                else:
                    added.append(summary)
            summaries.append(added)
        rate = self.false_alarm_rate if false_alarm_rate is None else false_alarm_rate
        return EffortModel.fitted(self.setups, summaries, self.dt_s, rate), notes

    def to_json(self) -> dict[str, Any]:
        groups = []
        for setup, logs, fit, why in zip(self.setups, self.summaries, self.fits, self.refused,
                                         strict=True):
            entry: dict[str, Any] = {
                "name": setup.group.name, "members": list(setup.group.members),
                "factors": list(setup.group.factors), "min_level": round(setup.min_level, 6),
                "level_edges": setup.edges.round(6).tolist(), "window_s": setup.window_s,
                "two_way": setup.two_way,
                **({} if setup.change_bin is None else {
                    "change_bin": setup.change_bin, "change_window_s": setup.change_window_s}),
                **({} if setup.group.reach is None else {
                    "reach": [list(row) for row in setup.group.reach]}),
                **({} if setup.group.balance is None else {
                    "balance": [list(row) for row in setup.group.balance]}),
                "driven_alone": setup.group.driven_alone,
                "logs": [g.to_json() for g in logs]}
            if fit is None:
                entry["refused"] = why
            else:
                entry["normal"] = _readable(fit, self.thresholds)
            groups.append(entry)
        return {"version": FORMAT_VERSION, "dt_s": self.dt_s,
                "false_alarm_rate": self.false_alarm_rate, "groups": groups}

    @classmethod
    def from_json(cls, entry: dict[str, Any]) -> "EffortModel":
        if entry.get("version") != FORMAT_VERSION:
            raise ValueError(f"effort model version {entry.get('version')} is not supported")
        setups, summaries = [], []
        for g in entry["groups"]:
            group = EffortGroup(str(g["name"]), tuple(g["members"]),
                                tuple(float(f) for f in g["factors"]), float(g["min_level"]),
                                float(g["window_s"]), as_table(g.get("reach")),
                                as_table(g.get("balance")),
                                bool(g.get("driven_alone", False)))
            setups.append(GroupSetup(group, float(g["min_level"]),
                                     np.asarray(g["level_edges"], float), float(g["window_s"]),
                                     bool(g["two_way"]),
                                     None if g.get("change_bin") is None else int(g["change_bin"]),
                                     float(g.get("change_window_s", 0.0))))
            summaries.append([GroupLog.from_json(s) for s in g["logs"]])
        return cls.fitted(setups, summaries, float(entry["dt_s"]),
                          float(entry["false_alarm_rate"]))


def _readable(fit: GroupFit, thresholds: Thresholds | None) -> dict[str, Any]:
    """What a reader of model.json wants to see; never read back."""
    share = fit.means.mean(axis=0) if not fit.conditioned else fit.means
    return {"share": np.round(share, 4).tolist(), "spread": fit.spread.round(4).tolist(),
            "within_window": fit.within.round(4).tolist(), "conditioned_on_level":
            fit.conditioned, "logs": fit.logs, "typical_steady_s": round(fit.typical_s, 2),
            "threshold_z": None if thresholds is None else round(thresholds.whole_log(fit), 3),
            "smallest_rise_judged": None if thresholds is None
            else np.round(smallest_rise(fit, thresholds), 4).tolist(),
            "leave_one_out_max_z": round(float(fit.loo_z.max()), 3), "logs_alike": fit.alike,
            "spread_widened": round(fit.widened, 4)}


def learn_effort(groups: Sequence[EffortGroup], logs: Sequence[EffortLog], dt_s: float,
                 false_alarm_rate: float = DEFAULT_FALSE_ALARM_RATE
                 ) -> tuple[EffortModel | None, list[str]]:
    """The effort model of ``groups`` from normal ``logs`` (None when no group has any
    steady effort at all), and notes on the logs left out."""
    setups = [s for g in groups if (s := _setup(g, logs, dt_s)) is not None]
    if not setups:
        return None, []
    notes: list[str] = []
    summaries = []
    for setup in setups:
        kept = []
        for log in logs:
            summary = setup.summarise(log, dt_s)
            if summary is None:
                notes.append(f"{log.name}: too little steady effort in {setup.group.name} "
                             f"(needs {setup.needs_s():.0f} s)")
            else:
                kept.append(summary)
        summaries.append(kept)
    return EffortModel.fitted(setups, summaries, dt_s, false_alarm_rate), notes


def change_fit(fit: GroupFit, setup: GroupSetup, logs: Sequence[GroupLog]) -> GroupFit | None:
    """``fit`` as its change bin's windows measure a change within a log: the bin's normal
    share; its windows' spread per member, the members' correlation there
    (`models.effort_correlation`) and the degrees of freedom of both (every log's windows);
    and the long windows' covariance, for a slow wander along a direction judged (None: no
    change bin, or no normal log with windows in it)."""
    inside = [g.change for g in logs if g.change is not None and g.change.within_cov is not None]
    if setup.change_bin is None or not inside:
        return None
    dof = sum(g.windows - 1 for g in inside)
    pooled = pooled_covariance([(g.within_cov, g.windows - 1) for g in inside])
    if pooled is None:
        return None
    sigma = np.sqrt(np.maximum(np.diag(pooled), SPREAD_FLOOR ** 2))
    slow = pooled_covariance([(g.long_cov, g.long_windows - 1) for g in inside
                              if g.long_cov is not None])
    return replace(fit, window_s=setup.change_window_s, conditioned=False,
                   means=fit.means[setup.change_bin:setup.change_bin + 1], within=sigma,
                   within_dof=float(dof),
                   within_corr=pooled_correlation([(g.within_cov, g.windows - 1)
                                                   for g in inside]),
                   within_slow=None if slow is None else LONG_WINDOW * slow
                   / np.outer(sigma, sigma))


def _change_bin(setup: GroupSetup, logs: Sequence[EffortLog]) -> GroupSetup:
    """``setup`` with its change bin, where its mixer cannot drive it member by member and
    one operating condition holds most of the normal logs' steady effort."""
    if setup.group.projection is None or not setup.two_way:
        return setup
    held = np.zeros(setup.n_bins)
    for log in logs:
        _, _, level, bins = setup.steady_steps(log)
        held += np.bincount(bins, weights=level, minlength=setup.n_bins)
    if held.sum() <= 0 or held.max() < MIN_CHANGE_SHARE * held.sum():
        return setup
    return replace(setup, change_bin=int(np.argmax(held)), change_window_s=max(
        MIN_WINDOW_S, setup.window_s / CHANGE_WINDOWS_PER_WINDOW))


def _setup(group: EffortGroup, logs: Sequence[EffortLog], dt_s: float) -> GroupSetup | None:
    """The steady level (the profile's, or half the median operating level), the level
    terciles and the window (the profile's, or a sixth of a typical log's steady time)."""
    usable_levels = []
    reverse = False
    for log in logs:
        _, level, usable = log.group_efforts(group)
        active = usable & (level > IDLE_LEVEL)
        usable_levels.append(level[active])
        reverse |= bool((log.group_commands(group)[active] < -IDLE_LEVEL).any())
    operating = np.concatenate(usable_levels) if usable_levels else np.empty(0)
    if not operating.size:
        return None
    min_level = group.min_level if group.min_level is not None else float(
        LEARNT_MIN_LEVEL * np.median(operating))
    steady = operating[operating >= min_level]
    if not steady.size:
        return None
    edges = np.quantile(steady, np.arange(1, LEVEL_BINS) / LEVEL_BINS)
    window_s = group.window_s
    if window_s is None:
        per_log = [float((u >= min_level).sum()) * dt_s for u in usable_levels]
        window_s = float(np.clip(np.median(per_log) / WINDOWS_PER_LOG, MIN_WINDOW_S,
                                 MAX_WINDOW_S))
    return _change_bin(GroupSetup(group, min_level, edges, window_s, reverse), logs)
