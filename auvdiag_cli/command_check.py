"""The commands judged against the motion: an actuator driven harder than the motion needs
(`models.command_relations`), which a controller hides from the motion itself."""

from dataclasses import dataclass

import numpy as np

from auvdiag_cli.profile import Profile
from models.command_relations import CommandRelations

NO_THRESHOLD = "not judged (too little held-out data drove it to set a threshold)"
NEVER_DRIVEN = "not judged (never driven enough in a window of this log)"


@dataclass(frozen=True)
class CommandCheck:
    command_names: tuple[str, ...]
    thresholds: dict[str, float | None]     # extra effort allowed (fraction); None: not judged
    not_judged: dict[str, str]              # command -> why
    ratio: np.ndarray                       # (steps, commands): extra effort / threshold
    peak_ratio: dict[str, float | None]
    alarm_s: float | None                   # end of the first window over a threshold
    named: tuple[str, ...]                  # components; several when they look the same
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
        if np.isnan(thresholds[k]):
            not_judged[name] = NO_THRESHOLD
        elif not finite.size:
            not_judged[name] = NEVER_DRIVEN
    first = _first_over(ratio)
    named: tuple[str, ...] = ()
    extra = None
    if first is not None:
        with np.errstate(invalid="ignore"):
            after = np.nanmean(np.where(np.isfinite(ratio[first:]), ratio[first:], np.nan),
                               axis=0)
        best = int(np.nanargmax(after))
        components = [profile.commands[k].component for k in relations.group_of(best)]
        named = tuple(dict.fromkeys(components))
        extra = round(float(np.nanmean(effort[first:, best])), 3)
    return CommandCheck(
        names, {n: None if np.isnan(t) else round(float(t), 4) for n, t in zip(
            names, thresholds, strict=True)}, not_judged, ratio, peaks,
        None if first is None else round(float(time_s[first]), 3), named, extra,
        relations.window_steps * relations.dt_s)
