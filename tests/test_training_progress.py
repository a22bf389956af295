"""Training's progress lines: the time left is estimated from the iterations after the
first, whose one-off costs would otherwise make it hundreds of times too long."""

import pytest

import models.training
from models.training import Stage, _Progress


def test_the_time_left_ignores_the_first_iterations_setup(monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:
    clock = iter([0.0, 120.0, 121.0, 122.0, 123.0, 124.0, 125.0])  # setup: 2 min, then 1 s
    monkeypatch.setattr(models.training.time, "perf_counter", lambda: next(clock))
    lines: list[str] = []
    progress = _Progress([Stage(10, 10, 1e-3)], [10], lines.append)
    progress.REPORT_EVERY_S = 0.5
    for iteration in range(6):
        progress.step(0, iteration, 0.1)
    # The first line has nothing to estimate from; then 1 s an iteration, 4 left after the 6th.
    assert lines[0] == "stage 1/1 (horizon 10 steps): 1/10 iterations, loss 0.10000"
    assert lines[-1].endswith("6/10 iterations, loss 0.10000, about 4 s left")
    assert all("min" not in line for line in lines)


def test_the_time_left_counts_the_networks_still_to_train(monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:
    """`train` fits the network alone, then again on top of the linear model: the first's
    time left includes the second's, so it does not reach 0 s with half the work to do."""
    clock = iter(float(t) for t in range(100))
    monkeypatch.setattr(models.training.time, "perf_counter", lambda: next(clock))
    lines: list[str] = []
    progress = _Progress([Stage(10, 10, 1e-3)], [10], lines.append, run=(1, 2))
    progress.REPORT_EVERY_S = 0.5
    for iteration in range(10):
        progress.step(0, iteration, 0.1)
    assert lines[-1] == ("network 1 of 2, stage 1/1 (horizon 10 steps): 10/10 iterations, "
                         "loss 0.10000, about 10 s left")
    last = _Progress([Stage(10, 10, 1e-3)], [10], lines.append, run=(2, 2))
    last.REPORT_EVERY_S = 0.5
    for iteration in range(10):
        last.step(0, iteration, 0.1)
    assert lines[-1].startswith("network 2 of 2, ") and lines[-1].endswith("about 0 s left")
