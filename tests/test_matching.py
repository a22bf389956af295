"""The index g, the vector b, the pattern table and the onset estimate."""

import numpy as np

from auvdiag_cli.engine.detection import binary_vector, detect, look_up
from auvdiag_cli.engine.residuals import residual_index


def test_g_is_the_mean_of_the_last_k_differences_in_percent_of_r():
    measured = np.asarray([[0.0], [0.1], [0.2], [0.3], [0.4]])
    modelled = np.zeros_like(measured)
    g = residual_index(measured, modelled, np.asarray([0.5]), window=2)
    # window 2: g(k) = 100/(2*0.5) * (|d(k-1)| + |d(k)|)
    np.testing.assert_allclose(g[:, 0], [0.0, 10.0, 30.0, 50.0, 70.0])


def test_g_skips_missing_samples_and_needs_half_a_window():
    measured = np.asarray([[0.1], [np.nan], [np.nan], [np.nan], [0.1], [0.1]])
    g = residual_index(measured, np.zeros_like(measured), np.asarray([1.0]), window=4)
    assert np.isnan(g[2, 0]) and np.isnan(g[3, 0])   # one valid sample of four
    np.testing.assert_allclose(g[5, 0], 10.0)        # two valid samples of four, mean 0.1


def test_b_uses_each_samples_threshold_and_never_alarms_on_nan():
    g = np.asarray([[5.0, np.nan], [9.0, 12.0]])
    thresholds = np.asarray([[8.0, 7.0], [15.0, 10.0]])
    np.testing.assert_array_equal(binary_vector(g, thresholds), [[0, 0], [0, 1]])


def test_pattern_table_lookup(profile):
    assert look_up(profile.pattern, {"flow": 1, "yaw_rate": 0}).components == ("flow_sensor",)
    assert look_up(profile.pattern, {"flow": 1, "yaw_rate": 1}).case == 1
    assert look_up(profile.pattern, {"flow": 0, "yaw_rate": 0}).components == ()


def test_detection_collects_b_over_the_decision_window_and_finds_the_onset():
    steps = 400
    rng = np.random.default_rng(0)
    residual = np.abs(rng.normal(0, 0.01, (steps, 2)))
    residual[200:, 0] += np.linspace(0, 1.0, steps - 200)   # first signal departs at 200
    residual[260:, 1] += 0.3                                 # second one a little later
    g = np.stack([np.convolve(residual[:, i], np.ones(20) / 20)[:steps] for i in (0, 1)], 1)
    thresholds = np.full((steps, 2), 10.0)
    b = binary_vector(100 * g, thresholds)
    found = detect(b, residual, thresholds, ("flow", "yaw_rate"), decision_steps=60,
                   lookback_steps=300)
    assert found is not None
    assert 200 < found.alarm_index < 260
    assert found.b == {"flow": 1, "yaw_rate": 1}
    assert abs(found.onset_index - 200) <= 10
    assert detect(np.zeros((10, 2), np.int8), residual[:10], thresholds[:10],
                  ("flow", "yaw_rate"), 5, 5) is None


def test_segments_from_markers(profile):
    from adapters import SegmentMarker
    from auvdiag_cli.engine.segments import segments_from_markers

    start = 1_000_000_000
    markers = [SegmentMarker(start + 2_000_000, "ZA"), SegmentMarker(start + 30 * 10**9, "zb"),
               SegmentMarker(start + 40 * 10**9, "ZB"), SegmentMarker(start + 60 * 10**9,
                                                                         "MISSION")]
    segments = segments_from_markers(markers, start, 100.0, profile)
    assert [(s.name, s.mode, s.start_s, s.end_s) for s in segments] == [
        ("ZA", "routine", 0.0, 30.0), ("ZB", "routine", 30.0, 60.0),
        ("MISSION", "mission", 60.0, 100.0)]
    assert segments[0].thresholds == {"flow": 8.0, "yaw_rate": 7.0}
    assert [s.name for s in segments_from_markers([], start, 100.0, profile)] == ["MISSION"]
    late = segments_from_markers([SegmentMarker(start + 5 * 10**9, "ZC")], start, 50.0, profile)
    assert [(s.name, s.start_s) for s in late] == [("MISSION", 0.0), ("ZC", 5.0)]
