"""A departure judged along a weak member's direction: the group's shares sum to one, so the
members' z are correlated and their projection must be scaled to keep Student's t honest."""

import numpy as np
import pytest
from quad_effort import PROFILE, SHARES, STEPS, quad_commands, quad_model

from auvdiag_cli.engine.effort_spans import Spans, cumulative
from models.effort_directions import judged_directions, weakness_directions
from models.effort_model import EffortLog


@pytest.mark.parametrize("members", [2, 3, 4, 6])
def test_departures_that_sum_to_zero_project_with_unit_variance(members):
    rng = np.random.default_rng(members)
    free = rng.standard_normal((20000, members))
    departures = free - free.mean(axis=1, keepdims=True)        # the shares average to one
    z = departures / departures.std(axis=0)                      # each member's own σ
    plain = (z @ weakness_directions(members).T).std(axis=0)
    judged = (z @ judged_directions(members).T).std(axis=0)
    assert np.allclose(plain, np.sqrt(members / (members - 1)), rtol=0.03)
    assert np.allclose(judged, 1.0, rtol=0.03)


def test_a_quadrotors_whole_log_statistic_is_of_unit_variance_on_normal_logs():
    """Four rotors learnt from 30 normal flights, each flight's trim off by its own random
    factor; 300 more normal flights: each member's z and the judged projection vary as a
    unit normal, the plain projection 4/3 as much."""
    rng = np.random.default_rng(5)
    means, spread = np.array([0.985, 1.002, 1.013, 1.000]), 0.025

    def flight() -> np.ndarray:
        return quad_commands(rng, (means + spread * rng.standard_normal(4)) / SHARES)

    model = quad_model([flight() for _ in range(30)])
    setup, fit = model.setups[0], model.fits[0]
    z = []
    for _ in range(300):
        log = EffortLog("normal", flight(), np.ones(STEPS, bool), PROFILE.command_names)
        _, effort, level, bins = setup.steady_steps(log)
        spans = Spans(fit, *cumulative(effort, level, bins, setup.n_bins), PROFILE.dt_s)
        z.append(spans.z(0, len(level))[0])
    members = np.array(z)
    judged = (members @ judged_directions(4).T).std(axis=0)
    plain = (members @ weakness_directions(4).T).std(axis=0)
    assert np.all(np.abs(members.std(axis=0) - 1.0) < 0.12)
    assert np.all(np.abs(judged - 1.0) < 0.12) and abs(judged.mean() - 1.0) < 0.06
    assert plain.mean() > 1.1
