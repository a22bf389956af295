"""Staged training of `RecurrentDynamics` by back-propagation through free-running rollouts.

Stages go from short horizons to long ones (the paper's staged training): a short rollout
teaches the one-step response, long rollouts teach the model to stay on track when only its
own output is fed back.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from models.dynamics import RecurrentDynamics, replay
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


@dataclass(frozen=True)
class FreeRunError:
    rms: tuple[float, ...]
    mean_abs: tuple[float, ...]


def fit_normaliser(sequences: Sequence[TrainingLog]) -> Normaliser:
    commands = np.concatenate([s.commands for s in sequences])
    sensors = np.concatenate([s.sensors for s in sequences])
    command_scale = np.maximum(np.nanmax(np.abs(commands), axis=0), 1e-6)
    state_scale = np.maximum(np.nanstd(sensors, axis=0), 1e-6)
    return Normaliser(tuple(float(v) for v in command_scale),
                      tuple(float(v) for v in state_scale))


def _windows(sequences: Sequence[TrainingLog], horizon: int, normaliser: Normaliser
             ) -> tuple[torch.Tensor, torch.Tensor]:
    """All windows of ``horizon`` steps (stride horizon/4) without missing sensor values."""
    commands, states = [], []
    for seq in sequences:
        stride = max(1, horizon // 4)
        for start in range(0, len(seq.commands) - horizon + 1, stride):
            window = seq.sensors[start:start + horizon]
            if np.isfinite(window).all():
                commands.append(seq.commands[start:start + horizon])
                states.append(window)
    if not commands:
        raise ValueError(f"no log is longer than {horizon} model steps")
    return normaliser.commands(np.stack(commands)), normaliser.states(np.stack(states))


def train(sequences: Sequence[TrainingLog], hidden: int = 32,
          stages: Sequence[Stage] = DEFAULT_STAGES, batch_size: int = 64, seed: int = 0,
          progress: Callable[[str], None] | None = None
          ) -> tuple[RecurrentDynamics, Normaliser]:
    """Train a model on normal-condition logs; returns the network and its normaliser."""
    torch.manual_seed(seed)
    generator = np.random.default_rng(seed)
    normaliser = fit_normaliser(sequences)
    n_commands, n_states = sequences[0].commands.shape[1], sequences[0].sensors.shape[1]
    network = RecurrentDynamics(n_commands, n_states, hidden, normaliser.delta_ratio)
    for number, stage in enumerate(stages, start=1):
        horizon = min(stage.horizon_steps, min(len(s.commands) for s in sequences))
        commands, states = _windows(sequences, horizon, normaliser)
        optimiser = torch.optim.Adam(network.parameters(), lr=stage.learning_rate)
        schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, stage.iterations)
        network.train()
        running = 0.0
        for iteration in range(stage.iterations):
            pick = torch.as_tensor(generator.integers(0, len(commands), batch_size))
            predicted = network(commands[pick], states[pick][:, 0])
            loss = torch.mean((predicted - states[pick]) ** 2)
            optimiser.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(network.parameters(), 1.0)
            optimiser.step()
            schedule.step()
            value = loss.item()
            running = 0.95 * running + 0.05 * value if iteration else value
        if progress is not None:
            progress(f"stage {number}/{len(stages)}: horizon {horizon} steps, "
                     f"{stage.iterations} iterations, loss {running:.5f}")
    network.eval()
    return network, normaliser


def free_run_error(network: RecurrentDynamics, normaliser: Normaliser,
                   sequences: Sequence[TrainingLog]) -> FreeRunError:
    """Error of whole-log free-running replays against the sensors, per state signal."""
    residuals = []
    for seq in sequences:
        predicted = replay(network, normaliser, seq.commands, seq.sensors[0])
        residuals.append(seq.sensors - predicted)
    stacked = np.concatenate(residuals)
    rms = np.sqrt(np.nanmean(stacked**2, axis=0))
    mean_abs = np.nanmean(np.abs(stacked), axis=0)
    return FreeRunError(tuple(float(v) for v in rms), tuple(float(v) for v in mean_abs))
