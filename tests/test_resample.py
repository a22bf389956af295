"""Alignment onto the model grid: hold, bin mean, cleaning and gaps."""

from pathlib import Path

import numpy as np
import pytest

from adapters import Signals
from adapters.signals import OPERATING, Series
from auvdiag_cli.engine.resample import resample
from auvdiag_cli.engine.silences import EDGE_S, silences

S = 1_000_000_000


def signals(**series: tuple[list[float], list[float]]) -> Signals:
    data = {name: Series(np.asarray([round(t * S) for t in times], dtype=np.int64),
                         np.asarray(values, dtype=float), name)
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


def _steady(start_s: float, stop_s: float, hz: float = 10.0) -> list[float]:
    return [start_s + i / hz for i in range(round((stop_s - start_s) * hz) + 1)]


def test_a_long_silence_is_left_off_the_grid_but_its_edges_stay():
    """A recorder paused for 9.8 h: the grid keeps the data and one minute at each end of
    the silence, on the same lattice; the replay restarts after it."""
    times = _steady(0.0, 40.0) + _steady(40.0 + 9.8 * 3600, 80.0 + 9.8 * 3600)
    frame = resample(signals(c=(times, [0.5] * len(times)), s=(times, [1.0] * len(times))),
                     ("c",), ("s",), 0.1, max_gap_s=1.0)
    assert len(frame.time_s) < (80 + 2 * EDGE_S) / 0.1 + 10      # not 353 000 steps
    np.testing.assert_allclose(frame.time_s / 0.1, np.round(frame.time_s / 0.1), atol=1e-6)
    jump = int(np.flatnonzero(np.diff(frame.time_s) > 1.0)[0])
    assert frame.time_s[jump] == pytest.approx(40.0 + EDGE_S, abs=0.11)
    assert frame.time_s[jump + 1] == pytest.approx(40.0 + 9.8 * 3600 - EDGE_S, abs=0.11)
    assert np.isnan(frame.sensors[(frame.time_s > 40.05) & (frame.time_s < 35320), 0]).all()
    assert np.isfinite(frame.sensors[frame.time_s > 35321, 0]).all()
    assert frame.restarts == [int(np.searchsorted(frame.time_s, 40.0 + 9.8 * 3600))]
    assert any("left off the model grid" in note for note in frame.notes)


def test_a_long_stretch_not_operating_is_left_off_but_a_short_one_is_not():
    times = _steady(0.0, 1000.0)
    armed = [1.0 if t < 100 or t >= 900 else 0.0 for t in times]     # 800 s on deck
    data = signals(c=(times, [0.5] * len(times)), s=(times, [1.0] * len(times)),
                   **{OPERATING: (times, armed)})
    frame = resample(data, ("c",), ("s",), 0.1)
    assert len(frame.time_s) == pytest.approx((200 + 2 * EDGE_S) / 0.1, abs=5)
    assert frame.not_operating_s == pytest.approx(800.0, abs=0.5)      # counted before
    assert frame.operating.sum() == pytest.approx(200 / 0.1, abs=5)
    short = [1.0 if t < 450 or t >= 550 else 0.0 for t in times]       # 100 s: kept
    frame = resample(signals(c=(times, [0.5] * len(times)), s=(times, [1.0] * len(times)),
                             **{OPERATING: (times, short)}), ("c",), ("s",), 0.1)
    assert len(frame.time_s) == len(times)
    assert not any("left off" in note for note in frame.notes)


def test_silences_are_where_every_signal_is_quiet():
    a = np.array([0, 10, 1000, 1010]) * S
    b = np.array([0, 200, 400, 600, 800, 1010]) * S
    assert silences([a, b], long_s=300) == []             # b talks inside a's silence
    b = np.array([0, 400, 1010]) * S                      # once: two silences either side
    assert silences([a, b], long_s=300) == [(10 * S, 400 * S), (400 * S, 1000 * S)]
    c = np.array([0, 5, 1005, 1010]) * S
    assert silences([a, c], long_s=300) == [(10 * S, 1000 * S)]


@pytest.mark.parametrize(("window", "min_periods"), [(7, 3), (31, 5), (6, 2)])
def test_the_centred_median_is_pandas_rolling_median(window, min_periods):
    """The spike finder's running median, in NumPy, gives what pandas' rolling median gave,
    gaps (NaN) and short ends included."""
    import pandas as pd

    from auvdiag_cli.engine.outliers import centred_median

    rng = np.random.default_rng(window)
    for size in (1, 2, 5, 40, 1000):
        values = rng.normal(size=size)
        values[rng.random(size) < 0.2] = np.nan
        expected = pd.Series(values).rolling(window, center=True,
                                             min_periods=min_periods).median().to_numpy()
        np.testing.assert_allclose(centred_median(values, window, min_periods), expected)


def test_outputs_are_held_for_the_effort_alone_and_shape_nothing_else():
    """An actuator output (read for the effort check only) that starts late, falls silent
    and comes back: held where heard, NaN before, inside its gap and where the log lacks it;
    the grid and the sensors are those without it."""
    times = [k / 10 for k in range(41)]
    late = [t for t in times if 0.8 <= t <= 1.5 or t >= 3.0]
    frame = resample(signals(c=(times, [0.5] * 41), s=(times, times),
                             out=(late, [2.0 if t < 2 else 3.0 for t in late]),
                             empty=([1.0], [float("nan")])),
                     ("c",), ("s",), 0.1, output_names=("out", "empty", "absent"))
    assert frame.time_s[0] == 0.0 and frame.time_s[-1] == pytest.approx(4.0)
    assert not np.isnan(frame.sensors).any() and not frame.restarts
    out = frame.outputs[:, 0]
    assert np.isnan(out[frame.time_s < 0.75]).all()
    assert (out[(frame.time_s > 0.75) & (frame.time_s < 1.55)] == 2.0).all()
    assert np.isnan(out[(frame.time_s > 1.6) & (frame.time_s < 2.9)]).all()
    assert (out[frame.time_s > 3.05] == 3.0).all()
    assert np.isnan(frame.outputs[:, 1:]).all()
    assert frame.efforts.shape == (len(frame.time_s), 4)
