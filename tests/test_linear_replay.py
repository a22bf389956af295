"""The linear model refined against the replay's error, on data where the one-step
least-squares fit is known to be biased: a first-order lag measured with noise."""

import numpy as np

from models.baselines import LinearDynamics, fit_linear
from models.linear_replay import fit_linear_to_replay
from models.rollouts import plan_rollouts, replay_plan

DECAY, GAIN = 0.05, 0.04        # x(k+1) = x(k) - DECAY x(k) + GAIN u(k)


def _lag(seed: int, steps: int = 2400, noise: float = 0.15
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Commands stepping every 3 s, the measured state (with noise) and the true one."""
    rng = np.random.default_rng(seed)
    commands = np.repeat(rng.uniform(-1, 1, steps // 30 + 1), 30)[:steps]
    state = np.zeros(steps)
    for k in range(1, steps):
        state[k] = state[k - 1] - DECAY * state[k - 1] + GAIN * commands[k - 1]
    return commands[:, None], (state + rng.normal(0, noise, steps))[:, None], state[:, None]


def _replay_error(weights: np.ndarray, seed: int) -> float:
    commands, measured, true = _lag(seed)
    plan = plan_rollouts(measured, (), 300)
    predicted = replay_plan(LinearDynamics(weights), commands, measured, plan, np.ones(1),
                            np.ones(1))
    return float(np.sqrt(np.nanmean((predicted - true) ** 2)))


def test_the_refined_fit_recovers_the_dynamics_least_squares_misses():
    logs = [_lag(seed) for seed in range(3)]
    least_squares = fit_linear([c for c, _, _ in logs], [m for _, m, _ in logs]).weights
    refined = fit_linear_to_replay([c for c, _, _ in logs], [m for _, m, _ in logs],
                                   [(), (), ()], least_squares, 300)
    assert refined is not None
    # The noise makes least squares see a decay several times too fast ...
    assert -least_squares[0, 0] > 3 * DECAY
    # ... the refined fit finds the vehicle's own within 10 %.
    np.testing.assert_allclose([-refined[0, 0], refined[1, 0]], [DECAY, GAIN], rtol=0.1)
    assert _replay_error(refined, 9) < 0.2 * _replay_error(least_squares, 9)


def test_nothing_to_replay_is_refused_with_the_reason():
    commands, measured, _ = _lag(0, steps=4)
    measured[:] = np.nan
    try:
        fit_linear_to_replay([commands], [measured], [()], np.zeros((3, 1)), 300)
    except ValueError as problem:
        assert "no stretch of complete data" in str(problem)
    else:
        raise AssertionError("an all-NaN log was fitted")
