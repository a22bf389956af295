"""What every form of the commands-against-the-motion relation shares: the logs it reads,
the windows it judges an actuator over, and the thresholds held-out normal logs set there
(`models.command_relations`, `models.thrust_relations`)."""

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol, Self

import numpy as np

from models.skill import MIN_SKILL

WINDOW_S = 30.0           # a weakness is persistent; a current or a gust averages out
MIN_WINDOW_S = 5.0        # logs too short for WINDOW_S: windows of half a log, this at least
# A stretch too short for the window is judged over a shorter one too, this share of it (at
# least MIN_WINDOW_S), with thresholds of its own: noisier, it sees a large extra effort only.
SHORTER_WINDOW = 1 / 3
MARGIN = 1.5              # thresholds: this many times the held-out normal peak
# The least share of thrust lost that either form judges over its main window (over a
# shorter one, as much more as its noise is: by the square root of how much shorter): the
# thrust a command gives drifts by a few percent with the battery, the water and the
# temperature. On the simulated quadrotor three normal missions set 2 % (thrust form) and
# 3 % extra command (commands' form), which normal missions of another seed crossed.
MIN_LOSS = 0.1


@dataclass(frozen=True)
class RelationLog:
    """One log on the model grid; ``usable`` marks the steps the relation may speak for
    (operating, outside open-loop test sequences)."""

    name: str
    commands: np.ndarray
    sensors: np.ndarray
    usable: np.ndarray
    efforts: np.ndarray | None = None   # the commands, then outputs only the effort reads


class RelationsRefused(ValueError):
    """The logs cannot teach the relation; the message says why."""


def trailing_sum(values: np.ndarray, steps: int) -> np.ndarray:
    """The sum over the ``steps`` ending at each step (along the first axis)."""
    total = np.cumsum(values, axis=0)
    total[steps:] = total[steps:] - total[:-steps]
    return total


def numbers_out(values: np.ndarray) -> list[float | None]:
    return [None if math.isnan(v) else round(v, 6) for v in values.tolist()]


def numbers_in(values: list[float | None]) -> np.ndarray:
    return np.asarray([math.nan if v is None else float(v) for v in values], float)


@dataclass(frozen=True)
class FittedOn:
    """What a relation was learned from."""

    logs: tuple[str, ...] = ()                  # the training logs fitted
    open_loop_left_out: tuple[str, ...] = ()    # training logs left out as open loop
    steps: int = 0                              # usable steps fitted
    heldout: tuple[str, ...] = ()               # the logs that set the thresholds
    heldout_judged_steps: tuple[int, ...] | None = None   # per actuator, in whole windows
    chosen: str = ""        # why this form of the relation was kept over the other

    def to_json(self) -> dict[str, object]:
        return {"logs": list(self.logs), "open_loop_left_out": list(self.open_loop_left_out),
                "steps": self.steps, "heldout": list(self.heldout),
                **({} if self.heldout_judged_steps is None
                   else {"heldout_judged_steps": list(self.heldout_judged_steps)}),
                **({"chosen": self.chosen} if self.chosen else {})}

    @classmethod
    def from_json(cls, entry: dict[str, Any]) -> "FittedOn":
        judged = entry.get("heldout_judged_steps")
        return cls(tuple(entry.get("logs", [])), tuple(entry.get("open_loop_left_out", [])),
                   int(entry.get("steps", 0)), tuple(entry.get("heldout", [])),
                   None if judged is None else tuple(int(n) for n in judged),
                   str(entry.get("chosen", "")))


@dataclass(frozen=True)
class RelationWindow:
    """A window of the judged measure and the most of it allowed over it."""

    steps: int
    thresholds: np.ndarray           # (n_commands,) allowed; NaN: not judged

    def to_json(self) -> dict[str, Any]:
        return {"window_steps": self.steps, "thresholds": numbers_out(self.thresholds)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "RelationWindow":
        return cls(int(data["window_steps"]), numbers_in(data["thresholds"]))


class WindowedRelations(ABC):
    """The windows and thresholds of a relation (a frozen dataclass with these fields)."""

    thresholds: np.ndarray           # (n_commands,) over the main window; NaN: not judged
    skill: np.ndarray                # (n_commands,)
    groups: tuple[tuple[int, ...], ...]
    dt_s: float
    window_steps: int
    fitted_on: FittedOn
    shorter: tuple[RelationWindow, ...]
    measure: str                     # what the windows measure ("extra effort", "thrust lost")

    @abstractmethod
    def as_loss(self, measured: np.ndarray) -> np.ndarray:
        """The share of thrust lost that this much of the measure makes up for."""

    @abstractmethod
    def from_loss(self, loss: float) -> float:
        """The measure that makes up for this share of thrust lost (`as_loss` inverted)."""

    def least_judged(self, window_steps: int) -> float:
        """The least of the measure judged over a window of ``window_steps`` (`least_loss`)."""
        return self.from_loss(least_loss(window_steps, self.window_steps))

    @property
    def windows(self) -> tuple[RelationWindow, ...]:
        """The main window first, then the shorter ones."""
        return (RelationWindow(self.window_steps, self.thresholds), *self.shorter)

    def window_label(self, index: int) -> str | None:
        """How window ``index`` of `windows` is named (None: the main one)."""
        return None if index == 0 else f"{self.windows[index].steps * self.dt_s:g} s window"

    @property
    def judges_anything(self) -> bool:
        """Some actuator has a threshold over some window."""
        return any(bool(np.isfinite(w.thresholds).any()) for w in self.windows)

    def with_window_thresholds(self, thresholds: Sequence[np.ndarray]) -> Self:
        """The same relations with new thresholds, one array per window of `windows`."""
        main, *rest = thresholds
        return replace(self, thresholds=main, shorter=tuple(    # type: ignore[type-var]
            replace(w, thresholds=t) for w, t in zip(self.shorter, rest, strict=True)))

    def too_little_heldout(self, k: int) -> str:
        """Why actuator k has no threshold though its relation has skill: how long the
        held-out logs drove it in whole windows, against one window's length."""
        judged = self.fitted_on.heldout_judged_steps
        steps = None if judged is None else judged[k]
        had = "" if steps is None else f"{steps * self.dt_s:.1f} s, "
        return (f"too little held-out data drove it to set a threshold ({had}needs "
                f"{self.window_steps * self.dt_s:g} s: one window)")

    def group_of(self, k: int) -> tuple[int, ...]:
        return next(g for g in self.groups if k in g)

    def windows_json(self) -> dict[str, Any]:
        """What every form writes of its windows, thresholds and fitting."""
        return {"thresholds": numbers_out(self.thresholds), "skill": numbers_out(self.skill),
                "groups": [list(g) for g in self.groups], "dt_s": self.dt_s,
                "window_steps": self.window_steps, "fitted_on": self.fitted_on.to_json(),
                **({"shorter_windows": [w.to_json() for w in self.shorter]} if self.shorter
                   else {})}

    def check_windows(self, m: int, what: str) -> None:
        """Raises ValueError where a window's thresholds do not fit ``m`` commands."""
        for window in self.windows:
            if window.steps < 1 or window.thresholds.shape != (m,):
                raise ValueError(f"{what}: a window of {window.steps} steps with "
                                 f"{window.thresholds.size} thresholds for {m} commands")


def windows_fields(data: dict[str, Any]) -> dict[str, Any]:
    """The fields `WindowedRelations.windows_json` wrote, read back (keyword arguments)."""
    return {"thresholds": numbers_in(data["thresholds"]), "skill": numbers_in(data["skill"]),
            "groups": tuple(tuple(int(i) for i in g) for g in data["groups"]),
            "dt_s": float(data["dt_s"]), "window_steps": int(data["window_steps"]),
            "fitted_on": FittedOn.from_json(data.get("fitted_on", {})),
            "shorter": tuple(RelationWindow.from_json(w)
                             for w in data.get("shorter_windows", []))}


class JudgesWindows(Protocol):
    def extra_effort(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray,
                     window_steps: int | None = None) -> np.ndarray: ...


SAME_SIGNATURE = 0.98     # cosine above which two actuators' signatures are the same


def groups_of(signatures: Sequence[np.ndarray]) -> tuple[tuple[int, ...], ...]:
    """Actuators whose signatures over the data coincide (up to scale): a check cannot
    tell them apart and names them together."""
    m = len(signatures)
    norms = [float(np.linalg.norm(s)) for s in signatures]
    parent = list(range(m))
    for i in range(m):
        for j in range(i + 1, m):
            if norms[i] > 0 and norms[j] > 0 and float(
                    signatures[i] @ signatures[j]) / (norms[i] * norms[j]) > SAME_SIGNATURE:
                parent[j] = parent[i]
    return tuple(tuple(k for k in range(m) if parent[k] == root)
                 for root in sorted(set(parent)))


def window_for(logs: Sequence[RelationLog], dt_s: float, longest_s: float = WINDOW_S
               ) -> float:
    """``longest_s``, or half the median log's usable time where logs are shorter than two
    windows (short flights, short runs), never below MIN_WINDOW_S."""
    usable_s = [float(log.usable.sum()) * dt_s for log in logs]
    if not usable_s:
        return longest_s
    return min(longest_s, max(MIN_WINDOW_S, float(np.median(usable_s)) / 2))


def window_steps_for(window_s: float, dt_s: float) -> tuple[int, int]:
    """The main window's steps and the shorter one's."""
    window = max(2, round(window_s / dt_s))
    return window, max(2, round(max(MIN_WINDOW_S, SHORTER_WINDOW * window_s) / dt_s))


def peaks_by_window(relations: JudgesWindows, logs: Sequence[RelationLog],
                    window_steps: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Over windows of ``window_steps``: each actuator's largest |measure| over these logs
    and how many steps judged it."""
    measured = [relations.extra_effort(h.commands, h.sensors, h.usable, window_steps)
                for h in logs]
    stacked = np.vstack(measured) if measured else np.full((0, m), np.nan)
    finite = np.isfinite(stacked)
    return (np.where(finite, np.abs(stacked), 0.0).max(axis=0, initial=0.0),
            finite.sum(axis=0))


def least_loss(window_steps: int, main_steps: int) -> float:
    """MIN_LOSS over a window of ``window_steps``, the main one of ``main_steps``."""
    return MIN_LOSS * math.sqrt(main_steps / window_steps)


def thresholds_from(peak: np.ndarray, judged_steps: np.ndarray, window_steps: int,
                    skill: np.ndarray, floor: float) -> np.ndarray:
    """MARGIN times the held-out peak, at least ``floor``; NaN where less than one window
    judged it, or its relation has no skill."""
    judged = (judged_steps >= window_steps) & (skill >= MIN_SKILL)
    return np.where(judged, np.maximum(MARGIN * peak, floor), np.nan)
