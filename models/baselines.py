"""Predictors that need no learning, the yardsticks of a model's skill.

- hold: the state the replay starts from holds (a model that predicts no change);
- mean: every signal sits at its mean over the training data;
- linear: x(k+1) = x(k) + [x(k), c(k), 1] @ W, fitted by least squares on one-step changes
  (the linear baseline of the detection benchmark).
All work in the model's normalised units and share the learned model's ``rollout`` interface
(commands (batch, steps, n_c), initial states (batch, n_s) → states (batch, steps, n_s);
``engine`` is accepted and ignored: there is nothing to compile).
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HoldLast:
    def rollout(self, commands: np.ndarray, initial_states: np.ndarray,
                engine: object = None) -> np.ndarray:
        steps = commands.shape[1]
        return np.repeat(initial_states[:, None, :].astype(np.float64), steps, axis=1)


@dataclass(frozen=True)
class TrainingMean:
    mean: np.ndarray              # (n_s,), normalised

    def rollout(self, commands: np.ndarray, initial_states: np.ndarray,
                engine: object = None) -> np.ndarray:
        batch, steps = commands.shape[:2]
        return np.broadcast_to(self.mean, (batch, steps, self.mean.size)).astype(np.float64)


@dataclass(frozen=True)
class LinearDynamics:
    weights: np.ndarray           # (n_s + n_c + 1, n_s)

    def rollout(self, commands: np.ndarray, initial_states: np.ndarray,
                engine: object = None) -> np.ndarray:
        batch, steps, _ = commands.shape
        states = np.empty((batch, steps, initial_states.shape[1]))
        state = initial_states.astype(np.float64)
        states[:, 0] = state
        with np.errstate(over="ignore", invalid="ignore"):   # an unstable fit diverges
            for k in range(steps - 1):
                features = np.hstack([state, commands[:, k], np.ones((batch, 1))])
                state = state + features @ self.weights
                states[:, k + 1] = state
        return states


def fit_linear(commands: Sequence[np.ndarray], sensors: Sequence[np.ndarray]
               ) -> LinearDynamics:
    """Least squares on every pair of consecutive samples with everything measured
    (normalised commands and sensors, one array per log)."""
    rows, targets = [], []
    for c, x in zip(commands, sensors, strict=True):
        ok = (np.isfinite(x[:-1]).all(axis=1) & np.isfinite(x[1:]).all(axis=1)
              & np.isfinite(c[:-1]).all(axis=1))
        rows.append(np.hstack([x[:-1], c[:-1], np.ones((len(x) - 1, 1))])[ok])
        targets.append((x[1:] - x[:-1])[ok])
    weights, *_ = np.linalg.lstsq(np.vstack(rows), np.vstack(targets), rcond=None)
    return LinearDynamics(weights)
