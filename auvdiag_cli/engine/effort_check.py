"""Each actuator's share of its group's effort in one log, against its normal band
(`models.effort`): an actuator whose share rises beyond its threshold is driven harder than
on normal logs, the mark of a damaged or fouled propeller, a weak motor or a load near it,
which the controller hides from the motion. A share that falls while another rises is the
normalisation (the shares of a group average to one), never a fault of its own.

Each test judges, per actuator, the group's departures (each in units of its σ) projected
on that actuator's signature (`models.effort_directions.judged_directions`): a weak
actuator's own share rises while the others fall; the departures sum to zero, so the
projection is scaled to the unit variance Student's t assumes. Two tests share the false-alarm
budget: the departure over the whole log's steady time from the normal logs' share, and
(for a fault that begins during the log) the departure of the span from each later start
to the end from the log's own span before that start. The second is blind to the log's own
offset from the normal logs (its battery, trim, payload), which is in both spans, and so
sees a weakness that begins mid-log far sooner. The detection is the moment from which the
span from the start that departs most stays past its threshold; the onset, the step that
departs most near the start that departs most among those tried on to the detection (the
change point's likeliest place, `effort_spans.date_change`)."""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.change_point import held_over
from auvdiag_cli.engine.effort_change import HELD_SHARE_OF_STRIDE, log_change
from auvdiag_cli.engine.effort_naming import (
    CLEAR_MATCH,
    ActuatorEffort,
    named_by_shares,
    not_ruled_out,
)
from auvdiag_cli.engine.effort_spans import (
    STARTS_PER_WINDOW,
    Spans,
    cumulative,
    rise_since,
)
from auvdiag_cli.engine.effort_words import carries, smallest_rise_shown
from auvdiag_cli.vehicle.profile import Profile
from models.effort import GroupFit, expected_share, window_shares
from models.effort_directions import judged_directions
from models.effort_model import EffortLog, EffortModel, GroupSetup
from models.effort_reach import named_signatures
from models.effort_thresholds import (
    MOST_LOGS_SAID,
    NEAR_RATE,
    Thresholds,
    logs_to_judge,
    smallest_rise,
)


@dataclass(frozen=True)
class EffortSeries:
    """A group's shares window by window, for the report's page."""

    group: str
    members: tuple[str, ...]
    time_s: np.ndarray          # (windows,) end of each window
    shares: np.ndarray          # (windows, members)
    normal: np.ndarray          # (windows, members) normal share for the window's conditions
    band: np.ndarray            # (members,) σ of one window's share about normal


# How a weakness is said where the profile does not give the actuators' kind.
MARINE_FAILURE = "a damaged or fouled propeller, a weak motor, or a load near it"


@dataclass(frozen=True)
class EffortCheck:
    actuators: tuple[ActuatorEffort, ...]
    false_alarm_rate: float      # the budget per log the thresholds were set for
    alarm_s: float | None
    onset_s: float | None
    named: tuple[str, ...]       # components of the actuators driven harder
    series: tuple[EffortSeries, ...]
    failure: str = ""            # how the suspects' kind of failure is said ("": marine words)
    # After an alarm, how well the departure of the suspect's group matches each member's
    # weakness (`signature_matches`), best first.
    matches: tuple[tuple[str, float], ...] = ()
    # How far the onset may lie from onset_s (None: the whole log departs, from its start).
    onset_error_s: float | None = None
    # The alarm is the whole log's departure from normal logs that differ no more than their
    # own noise makes them (`GroupFit.alike`): a normal log of another day may stray as far.
    against_alike_logs: bool = False
    # The members named in the suspect's group are ones its shares cannot tell apart
    # (`named_components`).
    cannot_tell_apart: bool = False
    # Where none alarmed: the component few normal logs cannot rule out weak
    # (`effort_naming.not_ruled_out`), and how its group's departure matches each member's
    # weakness, best first.
    not_ruled_out: str | None = None
    near_matches: tuple[tuple[str, float], ...] = ()

    @property
    def judged(self) -> bool:
        return any(a.not_judged is None for a in self.actuators)

    def told_by(self, motion: Sequence[str]) -> tuple[str, ...]:
        """The components named, or the one of those the shares cannot tell apart that the
        motion names (``motion``: the components the commands against the motion name;
        members a mixer moves alike in the shares act on the vehicle each its own way)."""
        told = tuple(c for c in self.named if c in motion)
        return told if self.cannot_tell_apart and len(told) == 1 else self.named

    def seen_with(self, motion: Sequence[str], alarm_s: float, onset_s: float | None
                  ) -> tuple[float | None, float | None]:
        """(Detection, onset): the effort's, or where the commands against the motion saw
        one of the same parts first (``motion``: the components they name, at ``alarm_s``,
        begun by ``onset_s``), their alarm, with the effort's onset where it comes before."""
        if not set(motion) & set(self.named) or (self.alarm_s is not None
                                                 and self.alarm_s <= alarm_s):
            return self.alarm_s, self.onset_s
        before = self.onset_s is not None and self.onset_s <= alarm_s
        return alarm_s, self.onset_s if before else onset_s

    def several(self) -> str:
        """What more than one component named means, to follow the description."""
        if self.cannot_tell_apart:
            return "; one of " + " or ".join(self.named) + ", which the shares cannot tell apart"
        if len(self.named) > 1:
            return "; more than one actuator is driven harder (a fault near several of them?)"
        return ""

    @property
    def clearly_one(self) -> str | None:
        """The one component named, where the shares match its actuator's weakness clearly
        (`CLEAR_MATCH`) and an alarm saw it; else None."""
        clear = (len(self.named) == 1 and self.matches and self.matches[0][1] >= CLEAR_MATCH
                 and self.alarm_s is not None)
        return self.named[0] if clear else None

    def alone_by(self, time_s: float | None, until_s: float | None = None) -> str | None:
        """`clearly_one`, where ``time_s`` (or a moment from it to ``until_s``) lies between
        the earliest it may have begun (its onset less the error stated) and when it was
        seen: the same event as one seen then."""
        if (time_s is None or self.onset_s is None or self.alarm_s is None
                or self.onset_error_s is None):
            return None
        end = time_s if until_s is None else until_s
        return self.clearly_one if (self.onset_s - self.onset_error_s <= end
                                    and time_s <= self.alarm_s) else None

    def throughout(self) -> str | None:
        """`clearly_one`, where the shares departed over the whole log against normal logs
        with no change within it: a weakness there from the log's start, so there whatever
        else was seen in it."""
        return self.clearly_one if self.onset_error_s is None else None

    @property
    def suspects(self) -> tuple[ActuatorEffort, ...]:
        return tuple(sorted((a for a in self.actuators if a.driven_harder),
                            key=lambda a: -(a.ratio or 0.0)))

    def describe(self) -> str:
        suspects = self.suspects
        if not suspects:
            judged = [a for a in self.actuators if a.not_judged is None]
            if not judged:
                return "not judged"
            worst = max(judged, key=lambda a: a.ratio or 0.0)
            lead = ("every actuator carries its normal share of the effort"
                    if self.not_ruled_out is None else "no actuator is past its threshold")
            return (f"{lead} (closest: {worst.said}, {worst.departure or 0.0:+.1%}, "
                    f"{worst.ratio or 0.0:.0%} of its threshold){self._not_ruled_out()}"
                    f"{smallest_rise_shown(judged)}")
        # A member its group's clear match leaves out (`named_components`) is not a weakness
        # of its own.
        parts = [carries(a) for a in suspects if a.component in self.named or not self.named]
        return ("; ".join(parts) + ": " + (self.failure or MARINE_FAILURE) + self._pattern()
                + self._since() + self._caution())

    def _not_ruled_out(self) -> str:
        """Why the few normal logs cannot rule out the actuator nearest its threshold."""
        if self.not_ruled_out is None or len(self.near_matches) < 2:
            return ""
        said = {a.name: a.said for a in self.actuators}
        (best, match), (second, other) = ((said.get(n, n), m) for n, m in self.near_matches[:2])
        return (f"; but {best} is past the threshold a {NEAR_RATE:.0%} budget would set, and "
                f"the shares match it weak ({match:.2f}; the next, {second}: {other:.2f}): "
                f"these few normal logs cannot rule out a weak {self.not_ruled_out} "
                f"({self._judged_with()})")

    def _judged_with(self) -> str:
        """How many normal logs like the model's would judge the one not ruled out."""
        logs = self.judged_with_logs
        if logs is None:
            return f"more would narrow its threshold; not even {MOST_LOGS_SAID} would judge it"
        return f"about {logs} normal logs like these would judge it"

    @property
    def judged_with_logs(self) -> int | None:
        """How many normal logs like the model's would judge the actuator not ruled out
        (None: none is, or more than MOST_LOGS_SAID would be needed)."""
        return next((a.judged_with_logs for a in self.actuators
                     if a.near and a.component == self.not_ruled_out), None)

    def _caution(self) -> str:
        return "" if not self.against_alike_logs else (
            "; caution: the normal logs it is judged against differ no more than their own "
            "noise makes them (logs of one day, it may be): a normal log of another day may "
            "stray this far")

    def _since(self) -> str:
        """When it began, where it began during the log."""
        if self.onset_s is None or self.onset_error_s is None:
            return ""
        return (f"; it began at ~{self.onset_s:.1f} s (give or take {self.onset_error_s:.1f} s) "
                f"and was seen at {self.alarm_s:.1f} s")

    def _pattern(self) -> str:
        if len(self.matches) < 2:
            return ""
        said = {a.name: a.said for a in self.actuators}
        (best, match), (second, other) = ((said.get(n, n), m) for n, m in self.matches[:2])
        if match < CLEAR_MATCH:
            return (f"; the shares match no one actuator's weakness well (closest {best}, "
                    f"{match:.2f}): more than one, or a load between them")
        pattern = f"; the shares match {best} weak ({match:.2f}; the next, {second}: {other:.2f})"
        if self.cannot_tell_apart:
            pattern += (", but where the vehicle worked its mix moves the shares of "
                        + " and ".join(self.named) + " nearly alike, and the departure that "
                        "alarmed leans too little towards one to tell which is weak")
        return pattern


def _judge_group(setup: GroupSetup, fit: GroupFit, change: GroupFit | None,
                 thresholds: Thresholds, log: EffortLog, time_s: np.ndarray, dt_s: float
                 ) -> tuple[np.ndarray, tuple[float, float | None] | None, float | None,
                            EffortSeries, tuple, tuple[np.ndarray | None, np.ndarray] | None]:
    """(ratio per actuator, (onset_s, its error: None for the whole log) after an alarm,
    alarm_s, series, whole-log figures (share, normal share, σ, signatures, the whole log's
    ratio to its threshold), (signatures, departures) of a change that alarmed,
    to name its member by)."""
    steady, effort, level, bins = setup.steady_steps(log)
    times = time_s[steady]
    window = setup.window_steps(dt_s)
    spans = Spans(fit, *cumulative(effort, level, bins, setup.n_bins), dt_s)
    n = len(level)
    toward = judged_directions(len(setup.group.members))
    within = log_change(setup, fit, change, thresholds, log, time_s, dt_s)
    # The whole log against the normal logs; each later start against the log before it.
    ratios = np.vstack([spans.z(0, n)[0] @ toward.T / thresholds.whole_log(fit),
                        within.ratios()])
    per_actuator = ratios.max(axis=0)
    share = effort.sum(axis=0) / level.sum()
    normal = expected_share(fit.means, np.bincount(bins, weights=level, minlength=setup.n_bins))
    sigma = fit.sigma(n * dt_s)
    commands = np.nan_to_num(log.group_commands(setup.group)[steady])
    figures = (share, normal, sigma, named_signatures(setup.group, commands, share, sigma),
               ratios[0])
    series = _series(setup, fit, effort, level, bins, times, window)
    top = int(np.argmax(per_actuator))
    if per_actuator[top] <= 1:
        return per_actuator, None, None, series, figures, None
    best = int(np.argmax(ratios[:, top]))
    if best == 0 and (ratios[1:, top] > 1).any():
        # The whole log departs because something changed within it (a rotor lost midway
        # moves the whole log's shares too): dated where it changed, not from the start.
        best = 1 + int(np.argmax(ratios[1:, top]))
    if best != 0:
        onset, alarm_s, departure = within.seen(top, within.starts[best - 1])
        return (per_actuator, onset, alarm_s, series, figures,
                (within.signatures, departure))
    # The whole log departs: seen from the first end, a window on, from which its
    # departure stays past its threshold (as `LogChange.seen`), and from its start.
    stride = max(1, window // STARTS_PER_WINDOW)
    running = (spans.z(0, np.arange(window, n + 1)) @ toward.T)[:, top]
    alarm = window + held_over(running, thresholds.whole_log(fit),
                               max(1, round(stride * HELD_SHARE_OF_STRIDE))) - 1
    return per_actuator, (float(times[0]), None), float(times[alarm]), series, figures, None


def _series(setup: GroupSetup, fit: GroupFit, effort: np.ndarray, level: np.ndarray,
            bins: np.ndarray, times: np.ndarray, window: int) -> EffortSeries:
    shares, last = window_shares(effort, level, window)
    normal = np.array([expected_share(fit.means, np.bincount(
        bins[i - window + 1:i + 1], weights=level[i - window + 1:i + 1],
        minlength=setup.n_bins)) for i in last]).reshape(len(last), -1)
    return EffortSeries(setup.group.name, setup.group.members, times[last], shares, normal,
                        fit.sigma(setup.window_s))


def _unread(members: Sequence[str], log: EffortLog) -> str | None:
    """Why a group cannot be judged on this log: an actuator the profile does not read, or
    an output this log lacks."""
    missing = [m for m in members if m not in log.command_names]
    if missing:
        return (f"not judged (the model's group holds {', '.join(missing)}, which the profile "
                "does not read)")
    columns = log.group_commands_of(members)
    absent = [m for k, m in enumerate(members) if not np.isfinite(columns[:, k]).any()]
    return f"not judged (this log has no {', '.join(absent)})" if absent else None


def _steady_s(setup: GroupSetup, fit: GroupFit | None, refused: str | None,
              model: EffortModel, log: EffortLog) -> tuple[float, str | None]:
    """The log's steady seconds in the group, and why it is not judged (None: it is)."""
    why = refused if refused is not None else _unread(setup.group.members, log)
    _, level, ok = log.group_efforts(setup.group)
    steady_s = float(setup.steady(level, ok).sum()) * model.dt_s
    if why is None and fit is not None and model.thresholds is not None \
            and steady_s < setup.needs_s():
        why = (f"not judged (too little steady effort in this log: {steady_s:.1f} s at "
               f"{setup.min_level:.3g} of full scale or more, needs {setup.needs_s():.0f} s)")
    return steady_s, why


def check_effort(model: EffortModel, profile: Profile, efforts: np.ndarray,
                 usable: np.ndarray, time_s: np.ndarray) -> EffortCheck:
    """Judge one log's effort shares (``efforts``: the commands, then the actuator outputs;
    ``usable``: operating and not a DMS run)."""
    log = EffortLog("", efforts, usable, profile.effort_names)
    component = {c.name: c.component for c in profile.effort_actuators}
    actuators: list[ActuatorEffort] = []
    series: list[EffortSeries] = []
    onsets: list[tuple[float, float, float | None, str]] = []   # alarm, onset, error, group
    directions: dict[str, np.ndarray] = {}     # each judged group's signatures, whole log
    changed: dict[str, np.ndarray] = {}        # a group's departures where a change alarmed
    changed_toward: dict[str, np.ndarray] = {}   # and the signatures to match them with
    alike = {setup.group.name for setup, fit in zip(model.setups, model.fits, strict=True)
             if fit is not None and fit.alike}
    for setup, fit, refused, change in zip(model.setups, model.fits, model.refused,
                                           model.change_fits or [None] * len(model.setups),
                                           strict=True):
        members = setup.group.members
        steady_s, why = _steady_s(setup, fit, refused, model, log)
        if why is not None or fit is None or model.thresholds is None:
            actuators += [ActuatorEffort(m, component.get(m, m), setup.group.name, None, None,
                                         None, None, None, why) for m in members]
            continue
        ratio, onset, alarm, group_series, (share, normal, sigma, toward, whole), departure = \
            _judge_group(setup, fit, change, model.thresholds, log, time_s, model.dt_s)
        near = model.thresholds.near(fit)
        past_near = np.zeros(len(members), bool) if near is None else \
            (whole >= near / model.thresholds.whole_log(fit)) & (ratio <= 1)
        directions[setup.group.name] = toward
        if departure is not None:
            signatures, changed[setup.group.name] = departure
            changed_toward[setup.group.name] = (toward if signatures is None
                                                else signatures[:, None, :])
        # Relative to this log's normal shares (its mix of levels or thrust directions).
        rise = smallest_rise(fit, model.thresholds, span_s=steady_s, shares=normal)
        since = None if onset is None or onset[1] is None else \
            rise_since(setup, log, time_s, onset[0])
        series.append(group_series)
        actuators += [ActuatorEffort(
            m, component[m], setup.group.name, round(float(share[k]), 4),
            round(float(normal[k]), 4), round(float(sigma[k]), 4),
            round(float(share[k] / normal[k] - 1), 4), round(float(ratio[k]), 3), None,
            round(float(rise[k]), 4), None if since is None else round(float(since[k]), 4),
            setup.group.driven_alone, bool(past_near[k]),
            logs_to_judge(fit, model.thresholds, float(whole[k])) if past_near[k] else None)
            for k, m in enumerate(members)]
        if alarm is not None and onset is not None:
            onsets.append((alarm, *onset, setup.group.name))
    matches, named, cannot_tell_apart = named_by_shares(actuators, directions, changed,
                                                        changed_toward)
    first = min(onsets, key=lambda o: (o[0], o[1]), default=None)
    kinds = {c.name: c.failure for c in profile.effort_actuators}
    failure = next((kinds[a.name] for a in actuators if a.driven_harder), "")
    return EffortCheck(tuple(actuators), model.false_alarm_rate,
                       None if first is None else round(first[0], 3),
                       None if first is None else round(first[1], 3), named, tuple(series),
                       failure, matches,
                       None if first is None or first[2] is None else round(first[2], 3),
                       first is not None and first[2] is None and first[3] in alike,
                       cannot_tell_apart, *not_ruled_out(actuators, directions))
