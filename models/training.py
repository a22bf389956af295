"""Staged training of `RecurrentDynamics` by back-propagation through free-running rollouts.

Stages go from short horizons to long ones (the paper's staged training): a short rollout
teaches the one-step response, long rollouts teach the model to stay on track when only its
own output is fed back.
"""

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from models.dynamics import RecurrentDynamics
from models.normaliser import Normaliser


@dataclass(frozen=True)
class TrainingLog:
    """One training log on the model grid: commands (steps, n_c), sensors (steps, n_s)."""

    name: str
    commands: np.ndarray
    sensors: np.ndarray


@dataclass(frozen=True)
class Stage:
    horizon_steps: int
    iterations: int
    learning_rate: float


DEFAULT_STAGES = (Stage(10, 400, 3e-3), Stage(50, 400, 2e-3), Stage(200, 400, 1e-3),
                  Stage(600, 150, 3e-4))


def fit_normaliser(sequences: Sequence[TrainingLog]) -> Normaliser:
    commands = np.concatenate([s.commands for s in sequences])
    sensors = np.concatenate([s.sensors for s in sequences])
    command_scale = np.maximum(np.nanmax(np.abs(commands), axis=0), 1e-6)
    state_scale = np.maximum(np.nanstd(sensors, axis=0), 1e-6)
    return Normaliser(tuple(float(v) for v in command_scale),
                      tuple(float(v) for v in state_scale))


def complete_stretches(sensors: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) of each run of steps with every sensor measured (gaps and time not
    operating are NaN)."""
    complete = np.isfinite(sensors).all(axis=1).astype(np.int8)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], complete, [0]))))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def longest_complete_stretch(sensors: np.ndarray) -> int:
    return max((end - start for start, end in complete_stretches(sensors)), default=0)


def _windows(sequences: Sequence[TrainingLog], horizon: int, normaliser: Normaliser
             ) -> tuple[torch.Tensor, torch.Tensor]:
    """All windows of ``horizon`` steps (stride horizon/4) inside stretches without missing
    sensor values."""
    commands, states = [], []
    stride = max(1, horizon // 4)
    for seq in sequences:
        for first, end in complete_stretches(seq.sensors):
            for start in range(first, end - horizon + 1, stride):
                commands.append(seq.commands[start:start + horizon])
                states.append(seq.sensors[start:start + horizon])
    if not commands:
        raise ValueError(f"no log is longer than {horizon} model steps")
    return normaliser.commands(np.stack(commands)), normaliser.states(np.stack(states))


class _Progress:
    """Progress inside the stages, with the time left estimated from the time per
    iteration-step so far (an iteration costs about its horizon in steps), counted from the
    end of the first iteration: the first carries one-off costs (the batches, the first
    pass through the network) that made its estimate hundreds of times too long."""

    REPORT_EVERY_S = 2.0

    def __init__(self, stages: Sequence[Stage], horizons: Sequence[int],
                 report: Callable[[str], None] | None, run: tuple[int, int] = (1, 1)) -> None:
        self.work = [s.iterations * h for s, h in zip(stages, horizons, strict=True)]
        self.stages, self.horizons, self.report = stages, horizons, report
        # Which of the trainings of one `train` job this is: the time left counts the ones
        # after it (each as long as this one), so it does not reach 0 s before they start.
        number, runs = run
        self.said = f"network {number} of {runs}, " if runs > 1 else ""
        self.total = sum(self.work) * (1 + runs - number)
        self.last = time.perf_counter()
        self.done = 0
        self.measured_from: tuple[float, int] | None = None   # (time, work done) then

    def step(self, stage: int, iteration: int, loss: float) -> None:
        self.done += self.horizons[stage]
        now = time.perf_counter()
        if self.measured_from is None:
            self.measured_from = (now, self.done)
        finished = iteration + 1 == self.stages[stage].iterations
        if self.report is None or not (finished or now - self.last >= self.REPORT_EVERY_S):
            return
        self.last = now
        since, done_then = self.measured_from
        rate = (now - since) / (self.done - done_then) if self.done > done_then else None
        left = "" if rate is None else \
            f", about {_duration(rate * (self.total - self.done))} left"
        iterations = self.stages[stage].iterations
        self.report(f"{self.said}stage {stage + 1}/{len(self.stages)} (horizon "
                    f"{self.horizons[stage]} steps): {iteration + 1}/{iterations} iterations, "
                    f"loss {loss:.5f}{left}")


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


def train(sequences: Sequence[TrainingLog], hidden: int = 32,
          stages: Sequence[Stage] = DEFAULT_STAGES, batch_size: int = 64, seed: int = 0,
          progress: Callable[[str], None] | None = None, linear: np.ndarray | None = None,
          run: tuple[int, int] = (1, 1)) -> tuple[RecurrentDynamics, Normaliser]:
    """Train a model on normal-condition logs; returns the network and its normaliser.
    ``linear``: a fixed linear model (normalised units) the network learns on top of.
    ``run``: (this training, how many the job trains alike), for the progress lines.

    Runs on one thread: the network's matrices are small, and a second thread only waits
    on the first (on a busy two-core machine it made training tens of times slower)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        return _train(sequences, hidden, stages, batch_size, seed,
                      _Progress(stages, _horizons(sequences, stages), progress, run), linear)
    finally:
        torch.set_num_threads(threads)


def _horizons(sequences: Sequence[TrainingLog], stages: Sequence[Stage]) -> list[int]:
    """Each stage's horizon: a window needs every sensor measured throughout, so not longer
    than the data allow."""
    longest = max(longest_complete_stretch(s.sensors) for s in sequences)
    if longest < 2:
        raise ValueError("no two consecutive samples with every sensor measured")
    return [min(stage.horizon_steps, longest) for stage in stages]


def _train(sequences: Sequence[TrainingLog], hidden: int, stages: Sequence[Stage],
           batch_size: int, seed: int, tracker: _Progress,
           linear: np.ndarray | None) -> tuple[RecurrentDynamics, Normaliser]:
    torch.manual_seed(seed)
    generator = np.random.default_rng(seed)
    normaliser = fit_normaliser(sequences)
    n_commands, n_states = sequences[0].commands.shape[1], sequences[0].sensors.shape[1]
    network = RecurrentDynamics(n_commands, n_states, hidden, normaliser.delta_ratio, linear)
    horizons = tracker.horizons
    for number, (stage, horizon) in enumerate(zip(stages, horizons, strict=True)):
        commands, states = _windows(sequences, horizon, normaliser)
        optimiser = torch.optim.Adam(network.parameters(), lr=stage.learning_rate)
        schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, stage.iterations)
        network.train()
        running = 0.0
        for iteration in range(stage.iterations):
            pick = torch.as_tensor(generator.integers(0, len(commands), batch_size))
            predicted = network(commands[pick], states[pick][:, 0])
            loss = torch.mean((predicted - states[pick]) ** 2)
            if not torch.isfinite(loss):    # a linear model under it that diverges
                raise ValueError(f"the rollouts diverge at a horizon of {horizon} steps")
            optimiser.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(network.parameters(), 1.0)
            optimiser.step()
            schedule.step()
            value = loss.item()
            running = 0.95 * running + 0.05 * value if iteration else value
            tracker.step(number, iteration, running)
    network.eval()
    return network, normaliser
