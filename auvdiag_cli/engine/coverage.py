"""How much of the vehicle a verdict looked at: which signals were judged, which actuators
(their commands against the motion, or their share of the effort), and whether the start
was. A NORMAL over less than the whole set is not the same claim as a NORMAL over all of
it, and every report says which one it is."""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.start_check import StartCheck


def normal_verdict_text(summary: str | None, complete: bool) -> str:
    """A NORMAL in words: bare only when everything was judged."""
    return "NORMAL: no fault detected" if complete or not summary else f"NORMAL on {summary}"


def _count(judged: Sequence[str], total: Sequence[str], noun: str) -> str:
    plural = noun if len(total) == 1 else noun + "s"
    return f"{len(judged)} of {len(total)} {plural}"


@dataclass(frozen=True)
class Coverage:
    signals: tuple[str, ...]
    signals_judged: tuple[str, ...]
    actuators: tuple[str, ...]
    actuators_judged: tuple[str, ...]
    start_judged: bool
    # Where only the change test judges the signals: from when (what came before is its
    # reference, where it sees nothing). None: from the start.
    judged_from_s: float | None = None

    @property
    def complete(self) -> bool:
        """Every signal and every actuator of the profile was judged, over the whole log."""
        return (self.judged_from_s is None and len(self.signals_judged) == len(self.signals)
                and len(self.actuators_judged) == len(self.actuators))

    @property
    def signals_not_judged(self) -> tuple[str, ...]:
        return tuple(s for s in self.signals if s not in self.signals_judged)

    @property
    def actuators_not_judged(self) -> tuple[str, ...]:
        return tuple(a for a in self.actuators if a not in self.actuators_judged)

    def counts(self) -> str:
        """"1 of 6 signals and 0 of 4 actuators judged" (no actuators: the signals only,
        as for a model driven by set points)."""
        signals = _count(self.signals_judged, self.signals, "signal")
        since = "" if self.judged_from_s is None else f" from {self.judged_from_s:.1f} s"
        if not self.actuators:
            return f"{signals} judged{since}"
        actuators = _count(self.actuators_judged, self.actuators, "actuator")
        return (f"{signals} and {actuators} judged" if not since
                else f"{signals} judged{since} and {actuators} judged")

    def describe(self) -> str:
        """The counts with the names left out, and the start."""
        missing = [*self.signals_not_judged, *self.actuators_not_judged]
        left_out = f" (not judged: {', '.join(missing)})" if missing else ""
        start = "start judged" if self.start_judged else "start not judged"
        return f"{self.counts()}{left_out}; {start}"

    def to_dict(self) -> dict[str, Any]:
        return {"summary": self.counts(), "complete": self.complete,
                "signals": {"judged": list(self.signals_judged),
                            "not_judged": list(self.signals_not_judged)},
                "actuators": {"judged": list(self.actuators_judged),
                              "not_judged": list(self.actuators_not_judged)},
                "start_judged": self.start_judged, "judged_from_s": self.judged_from_s}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Coverage":
        """Back from a JSON report's ``coverage`` (`to_dict`)."""
        signals, actuators = data["signals"], data["actuators"]
        return cls((*signals["judged"], *signals["not_judged"]), tuple(signals["judged"]),
                   (*actuators["judged"], *actuators["not_judged"]),
                   tuple(actuators["judged"]), bool(data.get("start_judged", False)),
                   data.get("judged_from_s"))


def coverage_of(signals: Sequence[str], not_judged: Sequence[str], actuators: Sequence[str],
                command_check: CommandCheck | None, effort_check: EffortCheck | None,
                start_check: StartCheck | None, judged_from_s: float | None = None
                ) -> Coverage:
    """An actuator counts as judged when its commands were judged against the motion
    somewhere in the log, or its share of its group's effort was."""
    by_commands = {name for name, peak in (command_check.peak_ratio.items()
                                           if command_check else ()) if peak is not None}
    by_effort = {a.name for a in (effort_check.actuators if effort_check else ())
                 if a.not_judged is None}
    return Coverage(tuple(signals), tuple(s for s in signals if s not in not_judged),
                    tuple(actuators),
                    tuple(a for a in actuators if a in by_commands | by_effort),
                    start_check is not None and start_check.judged, judged_from_s)
