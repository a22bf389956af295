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
