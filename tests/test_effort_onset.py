"""Where a weakness began, and how sure: the later starts whose statistic lies within the
95 % interval of one change point (3.84 in z² below the best one's), a stride at least; when
the last start tried is among them, the change may lie after it, up to when it was seen."""

import numpy as np
import pytest

from auvdiag_cli.engine.effort_check import _onset_error

STARTS = np.arange(10.0, 60.0, 2.0)      # s, a stride of 2 s
STRIDE = 2.0


def test_a_sharp_change_point_is_dated_to_a_stride():
    z = np.where(STARTS == 30.0, 10.0, 2.0)
    assert _onset_error(z, STARTS, int(np.argmax(z)), STRIDE, seen_s=33.0) == STRIDE


def test_a_flat_top_widens_the_error_to_its_likely_starts():
    z = 10.0 - 0.02 * np.abs(STARTS - 30.0)          # within 3.84 in z² up to 9.7 s away
    assert _onset_error(z, STARTS, int(np.argmax(z)), STRIDE, seen_s=45.0) == pytest.approx(8.0)


def test_a_change_after_the_last_start_reaches_to_when_it_was_seen_never_past_it():
    z = STARTS / 10.0                                 # rising to the last start tried, 58 s
    best = len(STARTS) - 1
    assert _onset_error(z, STARTS, best, STRIDE, seen_s=64.0) == pytest.approx(6.0)
    assert _onset_error(z, STARTS, best, STRIDE, seen_s=58.5) == pytest.approx(STRIDE)
