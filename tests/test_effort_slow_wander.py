"""A share that wanders slowly (a current, a tether, a disturbance slower than the judging
window) is not averaged out over a span a few windows long as independent windows would
be. The noise of one window is measured at a longer scale too, so that a normal log's last
minutes are not taken for a change; where the windows are independent, both scales agree."""

import numpy as np

from models.effort import LONG_WINDOW, summarise, within_and_dof

WINDOW, STEPS, DT_S = 20, 4000, 0.1


def _log(rng: np.random.Generator, correlation_steps: float):  # type: ignore[no-untyped-def]
    """Two actuators sharing a level of 1, the first's share wandering as a first-order
    process with this correlation time (0: independent steps), σ 0.02 of a share."""
    if correlation_steps:
        keep = np.exp(-1.0 / correlation_steps)
        drive = rng.normal(0.0, 0.02 * np.sqrt(1 - keep ** 2), STEPS)
        wander = np.zeros(STEPS)
        for k in range(1, STEPS):
            wander[k] = keep * wander[k - 1] + drive[k]
    else:
        wander = rng.normal(0.0, 0.02, STEPS)
    effort = np.column_stack([1.0 + wander, 1.0 - wander])
    level = effort.mean(axis=1)
    summary = summarise("log", effort, level, np.zeros(STEPS, int), 1, WINDOW, DT_S)
    assert summary is not None and summary.long_var is not None
    return summary, effort, level


def _short(logs) -> np.ndarray:  # type: ignore[no-untyped-def]
    dof = sum(g.windows - 1 for g in logs)
    return np.sqrt(np.sum([g.within_var * (g.windows - 1) for g in logs], axis=0) / dof)


def _late_z(effort: np.ndarray, level: np.ndarray, within: np.ndarray) -> float:
    """The last quarter's share against the three before, in the units the check uses."""
    cut = 3 * STEPS // 4
    before = effort[:cut].sum(axis=0) / level[:cut].sum()
    after = effort[cut:].sum(axis=0) / level[cut:].sum()
    spread = within * np.sqrt(WINDOW * DT_S * (1 / ((STEPS - cut) * DT_S) + 1 / (cut * DT_S)))
    return float(np.abs((after - before) / spread).max())


def test_a_slow_wander_widens_the_noise_of_a_span_and_keeps_late_spans_normal():
    rng = np.random.default_rng(3)
    # Correlated over two windows (a simulated ROV's roll disturbance against 2 s windows).
    learnt = [_log(rng, 2 * WINDOW)[0] for _ in range(12)]
    within, short = within_and_dof(learnt)[0], _short(learnt)
    assert np.all(within > 1.5 * short)
    fresh = [_log(rng, 2 * WINDOW) for _ in range(40)]
    # With the windows taken as independent, a normal log's late span stands 3 σ out now
    # and then; with the slow wander measured, not once in 40.
    assert sum(_late_z(e, lv, short) > 3 for _, e, lv in fresh) >= 4
    assert sum(_late_z(e, lv, within) > 3 for _, e, lv in fresh) == 0


def test_independent_windows_keep_the_short_measure():
    rng = np.random.default_rng(4)
    learnt = [_log(rng, 0)[0] for _ in range(12)]
    assert np.allclose(within_and_dof(learnt)[0], _short(learnt), rtol=0.2)
    assert learnt[0].long_windows == STEPS // (LONG_WINDOW * WINDOW)
