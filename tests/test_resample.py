"""Alignment onto the model grid: hold, bin mean, cleaning and gaps."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from adapters import Signals
from auvdiag_cli.engine.resample import resample

S = 1_000_000_000


def signals(**series: tuple[list[float], list[float]]) -> Signals:
    data = {name: pd.Series(values, index=np.asarray([round(t * S) for t in times]),
                            dtype=float)
            for name, (times, values) in series.items()}
    return Signals(Path("x.bag"), "bag", 0, 10 * S, data)


def test_commands_are_held_and_sensors_averaged():
    frame = resample(signals(
        c=([0.0, 0.25, 0.55], [1.0, 2.0, 3.0]),
        s=([0.0, 0.02, 0.04, 0.06, 0.08, 0.1, 0.12, 0.14, 0.16, 0.18, 0.2, 0.3, 0.4, 0.5, 0.6],
           [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14])),
        ("c",), ("s",), 0.1)
    np.testing.assert_allclose(frame.time_s, [0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    np.testing.assert_allclose(frame.commands[:, 0], [1, 1, 1, 2, 2, 2])
    # bin (t-0.1, t]: at 0.1 the samples 0.02..0.1 (1..5); at 0.2 the samples 0.12..0.2.
    np.testing.assert_allclose(frame.sensors[:, 0], [0, 3, 8, 11, 12, 13])


def test_empty_bins_are_interpolated_between_neighbours():
    frame = resample(signals(c=([0.0, 1.0], [0.0, 0.0]), s=([0.0, 0.4], [0.0, 4.0])),
                     ("c",), ("s",), 0.1)
    np.testing.assert_allclose(frame.sensors[:, 0], [0, 1, 2, 3, 4])


def test_unordered_duplicated_and_non_finite_samples_are_cleaned_and_reported():
    frame = resample(signals(c=([0.0, 0.3], [1.0, 1.0]),
                             s=([0.2, 0.0, 0.1, 0.1, 0.3, 0.25], [2.0, 0.0, 9.0, 1.0, 3.0,
                                                                  float("nan")])),
                     ("c",), ("s",), 0.1)
    np.testing.assert_allclose(frame.sensors[:, 0], [0, 1, 2, 3])
    text = " ".join(frame.notes)
    assert "out of time order" in text and "duplicate" in text and "non-finite" in text


def test_gaps_are_reported_and_never_interpolated_across():
    times = [i * 0.1 for i in range(10)] + [5.0 + i * 0.1 for i in range(10)]
    dense = [i * 0.1 for i in range(61)]
    frame = resample(signals(c=(dense, [0.0] * 61), s=(times, [1.0] * 20)),
                     ("c",), ("s",), 0.1, max_gap_s=1.0)
    inside = (frame.time_s > 0.95) & (frame.time_s < 4.95)
    assert np.isnan(frame.sensors[inside, 0]).all()
    assert np.isfinite(frame.sensors[~inside, 0]).all()
    assert len(frame.gaps) == 1 and frame.gaps[0].signal == "s"
    assert frame.gaps[0].start_s == pytest.approx(0.9) and frame.gaps[0].end_s == 5.0


def test_signals_that_never_overlap_are_refused():
    with pytest.raises(ValueError, match="overlap"):
        resample(signals(c=([0.0, 0.1], [0.0, 0.0]), s=([5.0, 6.0], [1.0, 1.0])),
                 ("c",), ("s",), 0.1)


def test_command_gap_blinds_sensors_and_restarts_the_replay():
    dense = [i * 0.1 for i in range(81)]
    commands = [i * 0.1 for i in range(20)] + [6.0 + i * 0.1 for i in range(21)]
    frame = resample(signals(c=(commands, [0.5] * 41), s=(dense, [1.0] * 81)),
                     ("c",), ("s",), 0.1, max_gap_s=1.0)
    inside = (frame.time_s > 1.95) & (frame.time_s < 5.95)
    assert np.isnan(frame.sensors[inside, 0]).all()
    assert frame.restarts == [60]
    assert [g.signal for g in frame.gaps] == ["c"]


def test_clock_jumping_back_is_retimed_and_reported():
    times = [10.0 + i * 0.1 for i in range(30)] + [1.0 + i * 0.1 for i in range(30)]
    values = list(range(60))
    frame = resample(signals(c=(times, [0.0] * 60), s=(times, values)), ("c",), ("s",), 0.1)
    assert frame.time_s[-1] == pytest.approx(15.9, abs=0.11)
    np.testing.assert_allclose(np.diff(frame.sensors[:, 0]), 1.0)
    assert any("clock jumps back by 11.9 s" in note for note in frame.notes)
