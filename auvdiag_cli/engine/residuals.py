"""Model Matching Part: replay the commands through the model and form the index g.

Window convention: g_i(k) = 100 / (K · R_i) · Σ_{j=k−K+1..k} |SS_i(j) − SM_i(j)|, i.e. the
mean of the last K absolute differences in percent of R_i (the paper sums K+1 terms and
divides by K; we average exactly K so that g is an unbiased mean). Samples missing inside a
reported gap are left out of the mean; g is NaN until half a window of samples exists.

The replay runs free from a robust estimate of the first measured state; it restarts from
the measured state at each *restart* (after a stretch of unknown commands, and at the start
of every Diagnosis Motion Sequence, which is a test of its own), and g's window never reaches
across one. A model with a finite prediction horizon also re-starts every horizon inside
those stretches (`models.rollouts`).
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.resample import AlignedFrame
from models.rollouts import plan_rollouts, replay_trials
from models.store import LoadedModel


@dataclass
class Matching:
    """SS, SM and g on the model grid, one column per sensed quantity."""

    measured: np.ndarray      # SS (steps, n_sensors)
    modelled: np.ndarray      # SM (steps, n_sensors)
    g_percent: np.ndarray     # g (steps, n_sensors)


def residual_index(measured: np.ndarray, modelled: np.ndarray, full_scale: np.ndarray,
                   window: int) -> np.ndarray:
    """g for every sample and signal, as in the module docstring."""
    difference = np.abs(measured - modelled) / full_scale
    valid = np.isfinite(difference)
    filled = np.where(valid, difference, 0.0)
    sums = np.cumsum(filled, axis=0)
    counts = np.cumsum(valid, axis=0)
    sums[window:] -= sums[:-window].copy()
    counts[window:] -= counts[:-window].copy()
    with np.errstate(invalid="ignore", divide="ignore"):
        g = 100.0 * sums / counts
    g[counts < max(1, window // 2)] = np.nan
    return g


def match(model: LoadedModel, frame: AlignedFrame, full_scale: dict[str, float],
          window: int, restarts: Sequence[int] = (), since: int = 0) -> Matching:
    """Replay the log's commands and compute g, restarting at ``frame.restarts`` and
    ``restarts`` (grid indices), and every horizon of the model inside them. Only g from
    step ``since`` on is wanted: rollouts that end a window or more before it are not run
    (SM and g stay NaN there)."""
    return match_trials(model, frame, [frame.commands], full_scale, window, restarts, since)[0]


def match_trials(model: LoadedModel, frame: AlignedFrame, trials: Sequence[np.ndarray],
                 full_scale: dict[str, float], window: int, restarts: Sequence[int] = (),
                 since: int = 0) -> list[Matching]:
    """`match` for each of several command histories (``trials``) of the log of
    ``frame``, replayed together (`models.rollouts.replay_trials`)."""
    measured = frame.sensors
    scales = np.asarray([full_scale[name] for name in frame.sensor_names])
    plan = [r for r in plan_rollouts(measured, [*frame.restarts, *restarts],
                                     model.horizon_steps) if r.end > since - window]
    replays = replay_trials(model.dynamics, [frame.drive_with(c) for c in trials],
                            measured, plan, np.asarray(model.normaliser.command_scale),
                            np.asarray(model.normaliser.state_scale))
    stretches = sorted({(r.stretch_begin, r.stretch_end) for r in plan})
    return [Matching(measured, modelled, _g_within(stretches, measured, modelled, scales,
                                                   window)) for modelled in replays]


def _g_within(stretches: Sequence[tuple[int, int]], measured: np.ndarray,
              modelled: np.ndarray, scales: np.ndarray, window: int) -> np.ndarray:
    """g where something was replayed; its window runs on across the model's own
    re-starts, never across a stretch's edge."""
    g = np.full_like(measured, np.nan)
    for begin, end in stretches:
        g[begin:end] = residual_index(measured[begin:end], modelled[begin:end], scales, window)
    return g
