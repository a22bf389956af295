"""The commands judged against the motion: an actuator driven harder than the motion needs
(`models.command_relations`), which a controller hides from the motion itself."""

from dataclasses import dataclass

import numpy as np

from auvdiag_cli.vehicle.profile import Profile
from models.command_relations import CommandRelations
from models.skill import MIN_SKILL

NO_THRESHOLD = "not judged (too little held-out data drove it to set a threshold)"
NEVER_DRIVEN = "not judged (never driven enough in a window of this log)"
# An actuator (or a group that acts alike) is named when its signature explains at least
# this share of the departure and DOMINANCE times the share any other explains: a weak
# thruster's explains most of it, while a sensor misreading the motion makes the controller
# push on several thrusters, each explaining part of it.
MIN_EXPLAINED = 0.1
DOMINANCE = 3.0


@dataclass(frozen=True)
class CommandCheck:
    command_names: tuple[str, ...]
    thresholds: dict[str, float | None]     # extra effort allowed (fraction); None: not judged
    not_judged: dict[str, str]              # command -> why
    ratio: np.ndarray                       # (steps, commands): extra effort / threshold
    peak_ratio: dict[str, float | None]
    alarm_s: float | None                   # end of the first window over a threshold
    named: tuple[str, ...]                  # components; several when they look the same
    explained: dict[str, float] | None      # share of the departure each actuator explains
    extra_effort: float | None              # the named actuator's mean extra effort after it
    window_s: float

    @property
    def judged(self) -> bool:
        """Some actuator was judged somewhere in this log."""
        return any(v is not None for v in self.peak_ratio.values())

    @property
    def onset_s(self) -> float | None:
        """The earliest the fault can have begun: the start of the first window over."""
        return None if self.alarm_s is None else max(0.0, self.alarm_s - self.window_s)

    def describe(self) -> str:
        if self.alarm_s is None:
            return "every judged actuator's command stayed within its relation to the motion"
        if not self.named:
            best = max((self.explained or {}).values(), default=0.0)
            return (f"the commands depart from what the motion needs from {self.alarm_s:.1f} s, "
                    f"but no single actuator explains it (at most {best:.0%}): a sensor "
                    "misreading the motion, or more than one fault")
        effort = "" if self.extra_effort is None else f" by {self.extra_effort:.0%} on average"
        return (f"{' or '.join(self.named)} driven harder than the motion needs{effort} "
                f"from {self.alarm_s:.1f} s ({self.window_s:.0f} s windows)")


def _first_over(ratio: np.ndarray) -> int | None:
    over = np.nan_to_num(ratio, nan=0.0).max(axis=1) > 1.0
    return int(np.argmax(over)) if over.any() else None


def check_commands(relations: CommandRelations, profile: Profile, commands: np.ndarray,
                   sensors: np.ndarray, usable: np.ndarray, time_s: np.ndarray
                   ) -> CommandCheck:
    effort = relations.extra_effort(commands, sensors, usable)
    thresholds = relations.thresholds
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = effort / thresholds
    names = profile.command_names
    not_judged: dict[str, str] = {}
    peaks: dict[str, float | None] = {}
    for k, name in enumerate(names):
        finite = ratio[:, k][np.isfinite(ratio[:, k])]
        peaks[name] = round(float(finite.max()), 3) if finite.size else None
        skill = relations.skill[k]
        if not skill >= MIN_SKILL:
            not_judged[name] = ("not judged (the relation does not predict its commands better "
                                "than their mean" + ("" if np.isnan(skill) else
                                                     f": skill {skill:.2f}") + ")")
        elif np.isnan(thresholds[k]):
            not_judged[name] = NO_THRESHOLD
        elif not finite.size:
            not_judged[name] = NEVER_DRIVEN
    first = _first_over(ratio)
    named: tuple[str, ...] = ()
    extra = shares = None
    if first is not None:
        since = usable.copy()
        since[:max(0, first - relations.window_steps)] = False
        shares = relations.explained(commands, sensors, since)
        best = int(np.argmax(shares))
        group = relations.group_of(best)
        others = max((shares[k] for k in range(len(names)) if k not in group), default=0.0)
        if shares[best] >= max(MIN_EXPLAINED, DOMINANCE * others):
            components = [profile.commands[k].component for k in group]
            named = tuple(dict.fromkeys(components))
            over = effort[first:, best][np.isfinite(effort[first:, best])]
            extra = round(float(over.mean()), 3) if over.size else None
    return CommandCheck(
        names, {n: None if np.isnan(t) else round(float(t), 4) for n, t in zip(
            names, thresholds, strict=True)}, not_judged, ratio, peaks,
        None if first is None else round(float(time_s[first]), 3), named,
        None if shares is None else {n: round(float(v), 3) for n, v in zip(
            names, shares, strict=True)}, extra,
        relations.window_steps * relations.dt_s)
