"""Where a replay starts, from what state, and for how long.

A log is cut into *stretches* (at gaps in the commands, time not operating, the start of
each Diagnosis Motion Sequence). Inside a stretch the model runs free, re-starting from the
measured state every ``horizon`` steps when the model has a finite prediction horizon
(``None``: the paper's pure free run, one rollout per stretch).

A rollout never starts from one raw sample: its state is the per-signal median of the
samples within ``START_HALF_WIDTH`` steps either side of the start (inside the stretch), so
one outlier cannot set it, and a straight ramp through the window is not biased. The first
rollout of a stretch starts that many steps in, so its window is whole.
"""

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from models.fast import expect_steps

START_HALF_WIDTH = 2          # a start state is the median of 5 samples


class Rollouts(Protocol):
    def rollout(self, commands: np.ndarray, initial_states: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class Rollout:
    stretch_begin: int        # the stretch this rollout lies in: [stretch_begin, stretch_end)
    stretch_end: int
    start: int                # predicted: [start, end)
    end: int


def plan_rollouts(sensors: np.ndarray, cuts: Sequence[int], horizon_steps: int | None
                  ) -> list[Rollout]:
    """The rollouts of a log of ``len(sensors)`` steps cut at ``cuts`` (grid indices). A
    rollout starts only where every signal has a sample in its start window; a re-start due
    where one has none waits for the next sample where all have."""
    bounds = sorted({0, len(sensors), *(c for c in cuts if 0 < c < len(sensors))})
    plan: list[Rollout] = []
    for begin, end in itertools.pairwise(bounds):
        startable = _startable(sensors[begin:end])
        candidates = np.flatnonzero(startable[START_HALF_WIDTH:]) + START_HALF_WIDTH + begin
        if not candidates.size:
            continue
        starts = [int(candidates[0])]
        while horizon_steps is not None:
            later = int(np.searchsorted(candidates, starts[-1] + horizon_steps))
            if later == candidates.size:
                break
            starts.append(int(candidates[later]))
        plan += [Rollout(begin, end, start, stop)
                 for start, stop in zip(starts, [*starts[1:], end], strict=True)]
    return plan


def _startable(sensors: np.ndarray) -> np.ndarray:
    """Where every signal has a measured sample within the start window."""
    measured = np.isfinite(sensors).astype(np.int64)
    width = 2 * START_HALF_WIDTH + 1
    padded = np.pad(measured, ((START_HALF_WIDTH, START_HALF_WIDTH), (0, 0)))
    counts = np.cumsum(np.vstack([np.zeros((1, sensors.shape[1]), np.int64), padded]), axis=0)
    return np.asarray(((counts[width:] - counts[:-width]) > 0).all(axis=1))


def robust_state(sensors: np.ndarray, index: int, begin: int = 0, end: int | None = None
                 ) -> np.ndarray:
    """The state at ``index``: per signal, the median of the measured samples within
    START_HALF_WIDTH steps of it, inside [begin, end); NaN where a signal has none."""
    stop = len(sensors) if end is None else end
    return robust_states(sensors, np.array([index]), np.array([begin]), np.array([stop]))[0]


def robust_states(sensors: np.ndarray, indices: np.ndarray, begins: np.ndarray,
                  ends: np.ndarray) -> np.ndarray:
    """`robust_state` at many indices at once, (len(indices), n_signals)."""
    offsets = indices[:, None] + np.arange(-START_HALF_WIDTH, START_HALF_WIDTH + 1)
    windows = sensors[np.clip(offsets, 0, len(sensors) - 1)]
    windows[(offsets < begins[:, None]) | (offsets >= ends[:, None])] = np.nan
    # NaN sorts last, so the measured samples lead and the median lies among them.
    ordered = np.sort(windows, axis=1)
    counts = np.isfinite(ordered).sum(axis=1, keepdims=True)
    lower = np.take_along_axis(ordered, np.maximum(counts - 1, 0) // 2, axis=1)[:, 0]
    upper = np.take_along_axis(ordered, counts // 2, axis=1)[:, 0]
    return np.where(counts[:, 0] > 0, (lower + upper) / 2, np.nan)


def start_states(sensors: np.ndarray, plan: Sequence[Rollout]) -> np.ndarray:
    """The robust state each rollout starts from (module docstring)."""
    def column(field: str) -> np.ndarray:
        return np.array([getattr(r, field) for r in plan], dtype=np.int64)

    return robust_states(sensors, column("start"), column("stretch_begin"),
                         column("stretch_end"))


def replay_plan(dynamics: Rollouts, commands: np.ndarray, sensors: np.ndarray,
                plan: Sequence[Rollout], command_scale: np.ndarray,
                state_scale: np.ndarray) -> np.ndarray:
    """Every rollout of ``plan`` advanced (in normalised units), in batches of rollouts of
    like length so that padding never doubles the memory; the prediction in physical units,
    NaN where nothing is predicted."""
    return replay_trials(dynamics, [commands], sensors, plan, command_scale, state_scale)[0]


def replay_trials(dynamics: Rollouts, trials: Sequence[np.ndarray], sensors: np.ndarray,
                  plan: Sequence[Rollout], command_scale: np.ndarray,
                  state_scale: np.ndarray) -> list[np.ndarray]:
    """`replay_plan` for several command histories of one log (trials: each actuator fault
    assumed in turn), all advancing together: each step's Python overhead is paid once for
    every trial, so they cost little more than one replay."""
    modelled = [np.full(sensors.shape, np.nan) for _ in trials]
    starts = start_states(sensors, plan) / state_scale if plan else np.empty((0, 0))
    batches = _batches_of_like_length(plan)
    expect_steps(sum(plan[rows[0]].end - plan[rows[0]].start for rows in batches))
    for rows in batches:
        longest = max(plan[row].end - plan[row].start for row in rows)
        batch = np.stack([np.pad(commands[plan[row].start:plan[row].end],
                                 ((0, longest - (plan[row].end - plan[row].start)), (0, 0)),
                                 mode="edge") for commands in trials for row in rows])
        states = dynamics.rollout((batch / command_scale).astype(np.float32),
                                  np.tile(starts[rows], (len(trials), 1)))
        for k, (trial, row) in enumerate(itertools.product(range(len(trials)), rows)):
            r = plan[row]
            modelled[trial][r.start:r.end] = states[k, :r.end - r.start].astype(np.float64) \
                * state_scale
    return modelled


def _batches_of_like_length(plan: Sequence[Rollout]) -> list[list[int]]:
    """Rollout indices, longest first, grouped while a group padded to its longest holds at
    most twice its own steps."""
    order = sorted(range(len(plan)), key=lambda i: plan[i].start - plan[i].end)
    batches: list[list[int]] = []
    for index in order:
        length = plan[index].end - plan[index].start
        if batches:
            group = batches[-1]
            longest = plan[group[0]].end - plan[group[0]].start
            held = sum(plan[i].end - plan[i].start for i in group) + length
            if longest * (len(group) + 1) <= 2 * held:
                group.append(index)
                continue
        batches.append([index])
    return batches
