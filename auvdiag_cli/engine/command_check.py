"""The commands judged against the motion: an actuator driven harder than the motion needs
(`models.command_relations`), or one whose thrust the motion shows less of than a healthy
one gives (`models.thrust_relations`), which a controller hides from the motion itself."""

from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.change_point import gain_start
from auvdiag_cli.vehicle.profile import Profile
from models.relation_forms import Relations
from models.skill import MIN_SKILL

# An actuator (or a group that acts alike) is named when its signature explains at least
# this share of the departure and DOMINANCE times the share any other explains: a weak
# thruster's explains most of it, while a sensor misreading the motion makes the controller
# push on several thrusters, each explaining part of it.
MIN_EXPLAINED = 0.1
DOMINANCE = 3.0
# A weakness persists; a manoeuvre the relation has not seen lifts a window's extra effort
# over its threshold for a few seconds only. The alarm stands once the windows over a
# threshold make up this share of the last window's length.
CONFIRM_WINDOWS = 1 / 6


@dataclass(frozen=True)
class CommandCheck:
    command_names: tuple[str, ...]
    thresholds: dict[str, float | None]     # extra effort allowed (fraction); None: not judged
    not_judged: dict[str, str]              # command -> why
    ratio: np.ndarray                       # (steps, commands): extra effort / threshold
    # Per window of the relations (the main one first), each command's peak extra effort
    # over its threshold there (None: not judged in this log).
    peak_by_window: tuple[dict[str, float | None], ...]
    alarm_s: float | None                   # when the windows over a threshold confirm it
    crossed_s: float | None                 # end of the first of those windows
    named: tuple[str, ...]                  # components; several when they look the same
    explained: dict[str, float] | None      # share of the departure each actuator explains
    extra_effort: float | None              # the named actuator's mean extra effort after it
    window_s: float                         # the window that alarmed (else the main one)
    # What the windows measure: "extra effort" (the command asked beyond what the motion
    # needs) or "thrust lost" (the share of its thrust the motion did not show).
    measure: str = "extra effort"
    # The sensors the finding rests on (the loss vanishes without their signal): only they
    # could be misreading instead; None: the relation cannot tell, any could.
    rests_on: tuple[str, ...] | None = None
    # Where the named actuator's loss most likely began (`change_point.gain_start`) and how
    # far off that may be; None: not dated within the first window over.
    began_s: float | None = None
    began_error_s: float | None = None

    @property
    def peak_ratio(self) -> dict[str, float | None]:
        """Each command's peak over its threshold in any window (None: never judged)."""
        peaks: dict[str, float | None] = {}
        for name in self.command_names:
            seen = [peak for p in self.peak_by_window if (peak := p.get(name)) is not None]
            peaks[name] = max(seen) if seen else None
        return peaks

    @property
    def judged(self) -> bool:
        """Some actuator was judged somewhere in this log."""
        return any(v is not None for v in self.peak_ratio.values())

    @property
    def earliest_s(self) -> float | None:
        """The earliest the fault can have begun: the start of the first window over."""
        return None if self.crossed_s is None else max(0.0, self.crossed_s - self.window_s)

    @property
    def onset_s(self) -> float | None:
        """When it most likely began, else the earliest it can have."""
        return self.earliest_s if self.began_s is None else self.began_s

    @property
    def onset_error_s(self) -> float | None:
        return self.began_error_s

    def describe(self) -> str:
        if self.alarm_s is None:
            return "every judged actuator's command stayed within its relation to the motion"
        if not self.named:
            best = max((self.explained or {}).values(), default=0.0)
            return (f"the commands depart from what the motion needs from {self.alarm_s:.1f} s, "
                    f"but no single actuator explains it (at most {best:.0%}): a sensor "
                    "misreading the motion, or more than one fault")
        named = " or ".join(self.named)
        since = f"from {self.alarm_s:.1f} s ({self.window_s:.0f} s windows)" + (
            "" if self.began_s is None else f"; it began at ~{self.began_s:.1f} s (give or "
            f"take {self.began_error_s or 0.0:.1f} s)")
        if self.measure == "thrust lost":
            lost = "" if self.extra_effort is None else f" ({self.extra_effort:.0%} on average)"
            return (f"{named} short of thrust: the motion shows less of it than a healthy "
                    f"one gives{lost} {since}")
        effort = "" if self.extra_effort is None else f" by {self.extra_effort:.0%} on average"
        return f"{named} driven harder than the motion needs{effort} {since}"


def _confirmed_alarm(ratio: np.ndarray, window_steps: int) -> tuple[int, int] | None:
    """(first step over, confirming step): the first step by which the windows over a
    threshold add up to CONFIRM_WINDOWS of the last window; None when they never do."""
    over = np.nan_to_num(ratio, nan=0.0).max(axis=1) > 1.0
    counts = np.cumsum(over)
    counts[window_steps:] -= counts[:-window_steps].copy()
    confirmed = np.flatnonzero(counts >= max(1, round(CONFIRM_WINDOWS * window_steps)))
    if not confirmed.size:
        return None
    at = int(confirmed[0])
    since = max(0, at - window_steps + 1)
    return since + int(np.argmax(over[since:at + 1])), at


def _dominant(shares: np.ndarray, groups: tuple[tuple[int, ...], ...], best: int
              ) -> tuple[int, ...]:
    """The actuators named: the best one's group where it explains at least MIN_EXPLAINED
    and DOMINANCE times what any other explains; else with the next group where the two
    together do and leave out as many actuators as they hold (two thrusters whose effects
    on the vehicle are alike in this log, named as either: a sensor misreading the motion
    spreads over many, and naming most of the actuators would say nothing); else none."""
    first = next(g for g in groups if best in g)
    rest = sorted((g for g in groups if g != first), key=lambda g: -max(shares[k] for k in g))
    pair = first + rest[0] if rest else ()
    for named in (first, pair) if 0 < 2 * len(pair) <= len(shares) else (first,):
        explained = sum(shares[k] for k in named) if named != first else shares[best]
        others = max((shares[k] for k in range(len(shares)) if k not in named), default=0.0)
        if explained >= max(MIN_EXPLAINED, DOMINANCE * others):
            return named
    return ()


def _peaks(ratio: np.ndarray, names: tuple[str, ...]) -> dict[str, float | None]:
    peaks: dict[str, float | None] = {}
    for k, name in enumerate(names):
        finite = ratio[:, k][np.isfinite(ratio[:, k])]
        peaks[name] = round(float(finite.max()), 3) if finite.size else None
    return peaks


def check_commands(relations: Relations, profile: Profile, commands: np.ndarray,
                   sensors: np.ndarray, usable: np.ndarray, time_s: np.ndarray
                   ) -> CommandCheck:
    """Each window of the relations judges the extra effort against its own thresholds;
    the first window to confirm an alarm gives it (a short stretch after a failure is seen
    by the shorter window, a small lasting weakness by the main one)."""
    names = profile.command_names
    windows = relations.windows
    efforts, ratios = [], []
    for window in windows:
        effort = relations.extra_effort(commands, sensors, usable, window.steps)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratios.append(effort / window.thresholds)
        efforts.append(effort)
    by_window = tuple(_peaks(r, names) for r in ratios)
    ratio = np.fmax.reduce(ratios) if len(ratios) > 1 else ratios[0]
    not_judged = _not_judged(relations, names, by_window)
    alarms = [(alarm, w) for w, r in enumerate(ratios)
              if (alarm := _confirmed_alarm(r, windows[w].steps)) is not None]
    alarm, which = min(alarms, key=lambda item: item[0][1]) if alarms else (None, 0)
    window_steps = windows[which].steps
    named: tuple[str, ...] = ()
    extra = shares = None
    rests_on: tuple[str, ...] | None = None
    began: tuple[float, float] | None = None
    if alarm is not None:
        first = alarm[0]
        since = usable.copy()
        since[:max(0, first - window_steps)] = False
        shares = relations.explained(commands, sensors, since)
        best = int(np.argmax(shares))
        group = _dominant(shares, relations.groups, best)
        if group:
            components = [profile.commands[k].component for k in group]
            named = tuple(dict.fromkeys(components))
            effort = efforts[which]
            over = effort[first:, best][np.isfinite(effort[first:, best])]
            extra = round(float(over.mean()), 3) if over.size else None
            signals = relations.rests_on(commands, sensors, since, group)
            rests_on = None if signals is None else tuple(
                profile.sensor_names[s] for s in signals)
            began = _began(relations, commands, sensors, usable, time_s, best,
                           (max(0, first - window_steps), first, alarm[1]))
    return CommandCheck(
        names, {n: None if np.isnan(t) else round(float(t), 4) for n, t in zip(
            names, relations.thresholds, strict=True)}, not_judged, ratio, by_window,
        None if alarm is None else round(float(time_s[alarm[1]]), 3),
        None if alarm is None else round(float(time_s[alarm[0]]), 3), named,
        None if shares is None else {n: round(float(v), 3) for n, v in zip(
            names, shares, strict=True)}, extra,
        window_steps * relations.dt_s, relations.measure, rests_on,
        *((None, None) if began is None else began))


def _not_judged(relations: Relations, names: tuple[str, ...],
                by_window: tuple[dict[str, float | None], ...]) -> dict[str, str]:
    """Why each actuator the relations cannot judge on this log is not judged."""
    shortest_s = min(w.steps for w in relations.windows) * relations.dt_s
    not_judged: dict[str, str] = {}
    for k, name in enumerate(names):
        skill = relations.skill[k]
        if not skill >= MIN_SKILL:
            not_judged[name] = (f"not judged ({relations.unpredicted(k)}"
                                + ("" if np.isnan(skill) else f": skill {skill:.2f}") + ")")
        elif all(np.isnan(w.thresholds[k]) for w in relations.windows):
            not_judged[name] = f"not judged ({relations.too_little_heldout(k)})"
        elif all(p[name] is None for p in by_window):
            not_judged[name] = f"not judged ({relations.undriven(shortest_s)})"
    return not_judged


def _began(relations: Relations, commands: np.ndarray, sensors: np.ndarray,
           usable: np.ndarray, time_s: np.ndarray, actuator: int,
           steps: tuple[int, int, int]) -> tuple[float, float] | None:
    """(When, give or take how much) the ``actuator``'s loss most likely began, between
    the start of the first window over and its end, judged up to the alarm (``steps``: those
    three); a window over dates it only to its length."""
    earliest, latest, at = steps
    numerator, weight = relations.step_terms(commands, sensors, usable)
    found = gain_start(numerator[:, actuator], weight[:, actuator], earliest, latest, at,
                       relations.dt_s)
    if found is None:
        return None
    best, first, last = (float(time_s[k]) for k in found)
    return round(best, 3), round(max(best - first, last - best, relations.dt_s), 3)
