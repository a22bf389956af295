"""The spike finder: isolated bad samples go, a fast but smooth swing of the signal stays."""

import numpy as np

from auvdiag_cli.engine.outliers import spike_mask


def _calm(size: int = 200, seed: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, 0.002, size)


def test_a_glitch_of_one_to_three_samples_is_a_spike():
    for width in (1, 2, 3):
        values = _calm()
        values[100:100 + width] += 0.8
        assert np.flatnonzero(spike_mask(values, 0.5)).tolist() == list(range(100, 100 + width))


def test_a_glitch_on_the_first_sample_is_a_spike():
    values = _calm()
    values[0] = 1.2
    assert np.flatnonzero(spike_mask(values, 0.5)).tolist() == [0]


def test_the_top_of_a_fast_smooth_swing_is_kept():
    # A yaw rate swinging to -0.9 rad/s and back within half a second as a rudder sticks
    # (the shape of ALFA's rudder failures at 10 Hz): its top stands out of the median of
    # 7, but the signal reaches it by its own motion.
    values = _calm()
    swing = np.array([-0.28, -0.77, -0.93, -0.91, -0.77, -0.48, -0.23, -0.13, -0.11, -0.17,
                      -0.27, -0.36, -0.41, -0.41, -0.36])
    values[100:100 + swing.size] += swing
    values[100 + swing.size:] += swing[-1]
    assert not spike_mask(values, 0.5).any()
    # The same swing with a glitch on its way down: the glitch alone goes.
    values[106] += 0.6
    assert np.flatnonzero(spike_mask(values, 0.5)).tolist() == [106]
