"""The NumPy replay path against the torch module it stands in for, on real trained models
and real logged command histories."""

import numpy as np
import pytest

from auvdiag_cli.ingest import ingest
from models.dynamics import replay
from models.fast import fast_replay, fast_replay_batch
from models.store import load_model


@pytest.mark.parametrize("vehicle", ["twin-burger", "three-thruster", "bluerov2"])
def test_numpy_path_matches_torch_on_random_command_steps(vehicle):
    model = load_model(None, vehicle)
    rng = np.random.default_rng(4)
    commands = np.repeat(rng.uniform(-0.8, 0.8, (60, len(model.command_names))), 40, axis=0)
    start = rng.normal(0.0, 0.05, len(model.sensor_names))
    reference = replay(model.network, model.normaliser, commands, start)
    fast = fast_replay(model.fast, model.normaliser, commands, start)
    np.testing.assert_allclose(fast, reference, rtol=0, atol=1e-6)


def test_numpy_path_matches_torch_on_a_logged_mission(make_log, profile):
    model = load_model()
    frame = ingest(make_log("paper-flow-sensor-covered", 11), profile).frame
    reference = replay(model.network, model.normaliser, frame.commands, frame.sensors[0])
    fast = fast_replay(model.fast, model.normaliser, frame.commands, frame.sensors[0])
    assert len(fast) > 1500
    np.testing.assert_allclose(fast, reference, rtol=0, atol=1e-6)


def test_batched_replays_equal_separate_ones():
    model = load_model()
    rng = np.random.default_rng(5)
    histories = [rng.uniform(-0.5, 0.5, (length, 2)) for length in (300, 17, 1, 120)]
    starts = [rng.normal(0.0, 0.05, 2) for _ in histories]
    batched = fast_replay_batch(model.fast, model.normaliser, histories, starts)
    for history, start, result in zip(histories, starts, batched, strict=True):
        assert result.shape == (len(history), 2)
        np.testing.assert_allclose(result, fast_replay(model.fast, model.normaliser, history,
                                                       start), rtol=0, atol=1e-6)
