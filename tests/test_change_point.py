"""Where a change began, and how sure. A grid of starts (the effort check's later starts):
the starts whose statistic lies within the 95 % interval of one change point (3.84 in z²
below the best one's) and on to the starts either side that fall short (the change lies
between two starts), a stride either side at least; when the last start tried is among
them, the change may lie after it, up to when it was seen. Steps (the change test's
residual): where its mean most likely shifted. A gain zero in normal operation (a thruster's
share of thrust lost): where it most likely became positive, in units of the noise its
correlated steps carry."""

import numpy as np
import pytest

from auvdiag_cli.engine.change_point import gain_start, likely_span, shift_start

STARTS = np.arange(10.0, 60.0, 2.0)      # s, a stride of 2 s
STRIDE = 2.0


def _span(z: np.ndarray, seen_s: float, starts: np.ndarray = STARTS) -> tuple[float, float]:
    return likely_span(z, starts, int(np.argmax(z)), STRIDE, seen_s)


def test_a_sharp_change_point_is_dated_to_a_stride_either_side():
    z = np.where(STARTS == 30.0, 10.0, 2.0)
    assert _span(z, seen_s=33.0) == (28.0, 32.0)


def test_a_flat_top_widens_the_span_to_its_likely_starts_and_the_next_ones_out():
    z = 10.0 - 0.02 * np.abs(STARTS - 30.0)          # within 3.84 in z² up to 9.7 s away
    # Likely: 22 to 38 s; the change lies after 20 s (short of it) and before 40 s.
    assert _span(z, seen_s=45.0) == pytest.approx((20.0, 40.0))


def test_a_change_after_the_last_start_reaches_to_when_it_was_seen_never_past_it():
    z = STARTS / 10.0                                 # rising to the last start tried, 58 s
    # Likely: 56 and 58 s; the change lies after 54 s, the last start that falls short.
    assert _span(z, seen_s=64.0) == pytest.approx((54.0, 64.0))
    assert _span(z, seen_s=58.5) == pytest.approx((54.0, 58.5))


def test_a_change_at_the_first_start_tried_may_lie_back_to_the_logs_start():
    """The first start tried has a span before it to be judged against: where the change
    is likeliest there, it may have begun anywhere in that span, back to the log's start
    (without the start given, a stride before)."""
    z = 10.0 - STARTS / 10.0                          # falling from the first start, 10 s
    assert _span(z, seen_s=20.0)[0] == pytest.approx(8.0)
    assert likely_span(z, STARTS, 0, STRIDE, 20.0, from_s=0.0)[0] == pytest.approx(0.0)


def test_a_change_after_a_gap_in_steady_time_may_lie_anywhere_in_the_gap():
    """The starts are a stride apart in steady time: where the group idled from 30 s to 40 s
    (no start there), a change first seen from 40 s may have begun at any time after 30 s."""
    starts = np.r_[np.arange(10.0, 31.0, 2.0), np.arange(40.0, 60.0, 2.0)]
    z = np.where(starts == 40.0, 10.0, 2.0)
    assert _span(z, seen_s=44.0, starts=starts) == pytest.approx((30.0, 42.0))


def test_the_steps_date_a_shift_within_the_span_they_are_given():
    rng = np.random.default_rng(3)
    values = rng.normal(0.0, 1.0, 400)
    values[250:] += 2.0
    assert abs(shift_start(values, 100, 320) - 250) <= 3
    # Never before the span's start, nor after the detection.
    assert shift_start(values, 260, 320) >= 260
    assert shift_start(values, 100, 100) == 100


def _gain_log(onset: int, gain: float, seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Per step, a thruster's shortfall along its part and its part's energy: the error
    correlated over 5 steps (a motion a moment ahead), the loss ``gain`` from ``onset``."""
    rng = np.random.default_rng(seed)
    weight = rng.uniform(0.5, 1.5, 1200)
    error = np.convolve(rng.normal(0.0, 1.0, 1204), np.ones(5) / np.sqrt(5), "valid")
    numerator = np.sqrt(weight) * error
    numerator[onset:] += gain * weight[onset:]
    return numerator, weight


def test_a_gain_is_dated_where_it_began_and_within_the_error_its_noise_allows():
    numerator, weight = _gain_log(800, 0.3)
    best, first, last = gain_start(numerator, weight, 600, 1000, 1100, 0.1) or (0, 0, 0)
    assert first <= 800 <= last and abs(best - 800) <= 30, (best, first, last)
    assert 600 <= first <= best <= last <= 1000
    # Twice the loss: dated closer.
    strong = gain_start(*_gain_log(800, 0.6), 600, 1000, 1100, 0.1) or (0, 0, 0)
    assert strong[2] - strong[1] < last - first and strong[1] <= 800 <= strong[2]


def test_a_gain_with_too_little_before_it_or_none_at_all_is_not_dated():
    numerator, weight = _gain_log(800, 0.3)
    assert gain_start(numerator, weight, 30, 1000, 1100, 0.1) is None      # 3 s before
    assert gain_start(-np.abs(numerator), weight, 600, 1000, 1100, 0.1) is None
