"""The NumPy replay path against the torch module it stands in for, on real trained models
and real logged command histories."""

import numpy as np
import pytest

from auvdiag_cli.engine.ingest import ingest
from models.dynamics import replay
from models.fast import fast_replay, fast_replay_batch
from models.store import load_model

ENGINES = ["numpy", "compiled"]


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("vehicle", ["twin-burger", "three-thruster", "bluerov2"])
def test_numpy_path_matches_torch_on_random_command_steps(vehicle, engine):
    model = load_model(None, vehicle)
    rng = np.random.default_rng(4)
    commands = np.repeat(rng.uniform(-0.8, 0.8, (60, len(model.command_names))), 40, axis=0)
    start = rng.normal(0.0, 0.05, len(model.sensor_names))
    reference = replay(model.network, model.normaliser, commands, start)
    fast = fast_replay(model.fast, model.normaliser, commands, start, engine)
    # Both run in float32 with their sums in different orders, and random steps drive a
    # model far outside what it learnt (the BlueROV2's roll rate to 40 of its spreads): the
    # rounding is judged against the largest state reached, in the model's own units.
    scale = np.asarray(model.normaliser.state_scale)
    extent = float(np.abs(reference / scale).max())
    np.testing.assert_allclose(fast / scale, reference / scale, rtol=0, atol=1e-5 * extent)


@pytest.mark.parametrize("engine", ENGINES)
def test_numpy_path_matches_torch_on_a_logged_mission(make_log, profile, engine):
    model = load_model()
    frame = ingest(make_log("paper-flow-sensor-covered", 11), profile).frame
    reference = replay(model.network, model.normaliser, frame.commands, frame.sensors[0])
    fast = fast_replay(model.fast, model.normaliser, frame.commands, frame.sensors[0], engine)
    assert len(fast) > 1500
    np.testing.assert_allclose(fast, reference, rtol=0, atol=1e-6)


@pytest.mark.parametrize("engine", ENGINES)
def test_batched_replays_equal_separate_ones(engine):
    model = load_model()
    rng = np.random.default_rng(5)
    histories = [rng.uniform(-0.5, 0.5, (length, 2)) for length in (300, 17, 1, 120)]
    starts = [rng.normal(0.0, 0.05, 2) for _ in histories]
    batched = fast_replay_batch(model.fast, model.normaliser, histories, starts, engine)
    for history, start, result in zip(histories, starts, batched, strict=True):
        assert result.shape == (len(history), 2)
        alone = fast_replay(model.fast, model.normaliser, history, start, "numpy")
        np.testing.assert_allclose(result, alone, rtol=0, atol=1e-6)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_nan_command_poisons_what_follows_and_nothing_before(engine):
    model = load_model()
    commands = np.full((200, 2), 0.3)
    commands[120, 0] = np.nan
    states = fast_replay(model.fast, model.normaliser, commands, np.zeros(2), engine)
    assert np.isfinite(states[:121]).all()
    assert np.isnan(states[121:]).all()


def test_long_replays_take_the_compiled_loop_and_short_ones_need_not():
    from models import fast

    fast.new_replay_budget()
    assert not fast._use_compiled("auto", 600)
    assert fast._use_compiled("auto", fast.COMPILED_PAYS_FROM_STEPS)
    assert not fast._use_compiled("numpy", 10**6)
    fast.expect_steps(fast.COMPILED_PAYS_FROM_STEPS)     # many short replays announced
    assert fast._use_compiled("auto", 600)
    fast.new_replay_budget()                             # the next log starts afresh
    assert not fast._use_compiled("auto", 600)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_replay_run_in_chunks_is_the_same_replay(monkeypatch, engine):
    """Long replays work out the commands' contributions a chunk at a time (bounded memory):
    the hidden state carried across chunk edges must make it the very same replay."""
    import models.fast

    model = load_model()
    rng = np.random.default_rng(6)
    commands = np.repeat(rng.uniform(-0.8, 0.8, (50, 2)), 20, axis=0)
    start = rng.normal(0.0, 0.05, 2)
    reference = replay(model.network, model.normaliser, commands, start)
    monkeypatch.setattr(models.fast, "CHUNK_VALUES", 7 * 3 * model.fast.hidden)
    chunked = fast_replay(model.fast, model.normaliser, commands, start, engine)
    np.testing.assert_allclose(chunked, reference, rtol=0, atol=1e-6)


def test_a_logs_figures_do_not_depend_on_what_the_process_did_before(make_log, profile):
    """One log after another in a process: one that needed the compiled loop (a long or
    faulty log) must not change the figures of the next, replayed on the NumPy loop."""
    from auvdiag_cli.engine.diagnosis import diagnose
    from models import fast
    from models.store import load_model

    model = load_model()
    log = make_log("paper-normal", 11)
    first = diagnose(log, profile, model)
    fast.expect_steps(fast.COMPILED_PAYS_FROM_STEPS)     # as a faulty log's isolation does
    again = diagnose(log, profile, model)
    assert np.array_equal(first.histories.matching.g_percent,
                          again.histories.matching.g_percent, equal_nan=True)


def test_an_audit_task_is_replayed_on_the_compiled_loop(monkeypatch, make_log):
    """An audit diagnoses log after log: within a task the compiled loop, loaded once a
    process, replays every log, short ones too (each replayed the same way, whatever came
    before it); the choice does not outlast the task."""
    from auvdiag_cli.audit.worker import AuditTask, analyse
    from models import fast

    compiled = fast.FastDynamics._compiled_rollout
    calls = []

    def counted(*args, **kwargs):
        calls.append(1)
        return compiled(*args, **kwargs)

    monkeypatch.setattr(fast.FastDynamics, "_compiled_rollout", counted)
    outcome = analyse(AuditTask(str(make_log("paper-normal", 11)), None, None))
    assert outcome.error is None and calls                # a 175 s log: NumPy alone
    fast.new_replay_budget()
    assert not fast._use_compiled("auto", 600)


def test_a_thread_replaying_many_logs_leaves_another_threads_diagnosis_alone(make_log,
                                                                              profile):
    """Which loop replays belongs to the work under way in its own thread: while one thread
    audits (every replay compiled), a diagnosis in another replays as it would alone."""
    import threading

    from auvdiag_cli.engine.diagnosis import diagnose
    from models import fast

    model = load_model()
    log = make_log("paper-normal", 11)
    alone = diagnose(log, profile, model)
    auditing, done = threading.Event(), threading.Event()

    def audit() -> None:
        with fast.replaying_many_logs():
            auditing.set()
            done.wait(60)

    other = threading.Thread(target=audit)
    other.start()
    try:
        assert auditing.wait(60)
        assert not fast._use_compiled("auto", 600)
        beside = diagnose(log, profile, model)
    finally:
        done.set()
        other.join()
    assert np.array_equal(alone.histories.matching.g_percent,
                          beside.histories.matching.g_percent, equal_nan=True)
