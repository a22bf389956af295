"""The linear model fitted to the replay rather than to one step.

Least squares (`models.baselines.fit_linear`) fits x(k+1) - x(k) one step ahead from the
measured state; a diagnosis runs the model free for many steps from a start state, where a
small bias in the one-step fit grows. This refines the same weights W against the error of
free rollouts of the training logs, planned as a diagnosis plans them (`models.rollouts`),
each signal's error counted relative to the least-squares fit's so that no signal's units
outweigh another's. Held-out skill decides whether it is kept (`jobs.candidates`).
"""

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from models.rollouts import plan_rollouts, robust_state

if TYPE_CHECKING:
    import torch

# Rollouts the fit runs: windows of at most this many steps (a minute at 10 Hz), at most
# this many of them (chosen evenly through the logs): the cost stays a few seconds for a
# day of logs.
WINDOW_STEPS_MAX = 600
WINDOWS_MAX = 512
ITERATIONS = 100            # in the last stage; the earlier ones take half
STAGE_FIRST_STEPS = 10
STAGE_GROWTH = 4            # each stage's windows this many times the last's


def _windows(commands: Sequence[np.ndarray], sensors: Sequence[np.ndarray],
             cuts: Sequence[Sequence[int]], window_steps: int
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Commands (n, steps, n_c), start states (n, n_s) and measured states (n, steps, n_s;
    NaN where nothing was measured or after a window's end), normalised units."""
    found = []
    for c, x, log_cuts in zip(commands, sensors, cuts, strict=True):
        for r in plan_rollouts(x, log_cuts, window_steps):
            if r.end - r.start > 1:
                found.append((c[r.start:r.end], robust_state(x, r.start, r.stretch_begin,
                                                             r.stretch_end), x[r.start:r.end]))
    if not found:
        raise ValueError("no stretch of complete data long enough to replay")
    if len(found) > WINDOWS_MAX:
        found = [found[i] for i in np.linspace(0, len(found) - 1, WINDOWS_MAX).astype(int)]
    steps = max(len(c) for c, _, _ in found)
    n_c, n_s = found[0][0].shape[1], found[0][2].shape[1]
    window_commands = np.zeros((len(found), steps, n_c))
    measured = np.full((len(found), steps, n_s), np.nan)
    for i, (c, _, x) in enumerate(found):
        window_commands[i, :len(c)] = np.nan_to_num(c)
        measured[i, :len(x)] = x
    starts = np.nan_to_num(np.array([s for _, s, _ in found]))
    return window_commands, starts, measured


def _replay_error(window_commands: np.ndarray, starts: np.ndarray, measured: np.ndarray
                  ) -> "Callable[[torch.Tensor], torch.Tensor]":
    """Each signal's mean squared error of free rollouts over the windows, for weights W."""
    import torch

    c, x0 = torch.from_numpy(window_commands), torch.from_numpy(starts)
    seen = torch.from_numpy(np.isfinite(measured))
    target = torch.from_numpy(np.nan_to_num(measured))
    counts = seen.sum(dim=(0, 1)).clamp(min=1)
    n_s = x0.shape[1]

    def error(weights: torch.Tensor) -> torch.Tensor:
        # x(k+1) = x(k) A + d(k): the commands' part for every step at once, then one
        # product and one sum a step (the loop is what costs).
        transition = torch.eye(n_s, dtype=torch.float64) + weights[:n_s]
        drive = c @ weights[n_s:-1] + weights[-1]
        state, predicted = x0, [x0]
        for k in range(c.shape[1] - 1):
            state = state @ transition + drive[:, k]
            predicted.append(state)
        residual = torch.where(seen, torch.stack(predicted, 1) - target, 0.0)
        return (residual ** 2).sum(dim=(0, 1)) / counts

    return error


def _descend(error: "Callable[[torch.Tensor], torch.Tensor]", start: np.ndarray,
             scale: "torch.Tensor", iterations: int) -> np.ndarray:
    """L-BFGS from ``start``; the weights with the lowest finite error seen (a step that
    makes the recurrence unstable overflows, and must not end the fit there)."""
    import torch

    weights = torch.tensor(start, dtype=torch.float64, requires_grad=True)
    best: list[tuple[float, np.ndarray]] = [(float("inf"), start)]
    optimiser = torch.optim.LBFGS([weights], max_iter=iterations,
                                  line_search_fn="strong_wolfe")

    def closure() -> torch.Tensor:
        optimiser.zero_grad()
        loss = (error(weights) / scale).sum()
        if torch.isfinite(loss):
            loss.backward()
            value = float(loss.detach())
            if value < best[0][0]:
                best[0] = (value, weights.detach().numpy().copy())
        return loss

    optimiser.step(closure)     # type: ignore[no-untyped-call]
    return best[0][1]


def fit_linear_to_replay(commands: Sequence[np.ndarray], sensors: Sequence[np.ndarray],
                         cuts: Sequence[Sequence[int]], least_squares: np.ndarray,
                         window_steps: int) -> np.ndarray | None:
    """W refined from ``least_squares`` against free-rollout error over windows of
    ``window_steps`` (normalised commands and sensors, one array per log); None where the
    refinement does not lower the replay error (there was nothing to gain). The windows
    lengthen in stages from STAGE_FIRST_STEPS by STAGE_GROWTH, each starting where the last ended:
    over long windows the error of a linear recurrence is too steep to start on."""
    import torch

    full = min(window_steps, WINDOW_STEPS_MAX)
    lengths = [h for h in (STAGE_FIRST_STEPS * STAGE_GROWTH ** k for k in range(16)) if h < full]
    weights = least_squares.astype(np.float64)
    reference: torch.Tensor | None = None
    for steps in [*lengths, full]:
        error = _replay_error(*_windows(commands, sensors, cuts, steps))
        with torch.no_grad():
            at_start = error(torch.from_numpy(weights))
            reference = error(torch.from_numpy(least_squares.astype(np.float64)))
        finite = torch.isfinite(reference).all()
        scale = reference.clamp(min=1e-12) if finite else at_start.clamp(min=1e-12)
        weights = _descend(error, weights, scale,
                           ITERATIONS if steps == full else ITERATIONS // 2)
    assert reference is not None
    with torch.no_grad():
        refined = error(torch.from_numpy(weights))
    if torch.isfinite(reference).all() and not (refined / reference.clamp(min=1e-12)).sum() < len(
            reference):
        return None
    result: np.ndarray = weights.astype(np.float32)
    return result
