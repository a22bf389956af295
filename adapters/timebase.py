"""Timestamps as damaged logs store them: a flipped bit in one record's time must cost that
record, not the log. Times are integer nanoseconds (int64) everywhere after this module."""

import numpy as np

# Larger raw times are not times: µs or ns this far out overflow int64 nanoseconds, and no
# clock since boot or since 1970 reaches them (2^53 µs is 285 years).
MAX_TIME_US = 1 << 53
MAX_TIME_NS = 1 << 62
# A stored time is a spike when it disagrees with both neighbours by more than this while
# they agree with each other: one corrupted record, not a clock jump or a gap.
SPIKE_TOLERANCE_NS = 1_000_000_000
END_SPIKE_RATIO = 100
# Neighbours a gap apart (a damaged stretch was skipped) still unmask a time that lies
# outside both of them, this many times further away than they are from each other.
GAP_SPIKE_RATIO = 10


def plausible_us(times_us: np.ndarray) -> np.ndarray:
    """Which raw µs times can be times at all (as unsigned values read from a file)."""
    return (times_us >= 0) & (times_us < MAX_TIME_US)


def spikes(times_ns: np.ndarray, tolerance_ns: int = SPIKE_TOLERANCE_NS) -> np.ndarray:
    """Mask of isolated times, in stored order, that are far from both neighbours while the
    neighbours are close to each other, or lie outside both far beyond the gap between
    them (at the ends: far from the next, which is close to
    the one after)."""
    times = np.asarray(times_ns, dtype=np.int64)
    mask = np.zeros(times.size, bool)
    if times.size < 3:
        return mask
    # Differences in float: two corrupt times can be 2^63 apart.
    as_float = times.astype(np.float64)
    step = np.abs(np.diff(as_float))
    far_before, far_after = step[:-1] > tolerance_ns, step[1:] > tolerance_ns
    neighbour_gap = np.abs(as_float[2:] - as_float[:-2])
    middle = as_float[1:-1]
    outside = (middle > np.maximum(as_float[:-2], as_float[2:])) | (
        middle < np.minimum(as_float[:-2], as_float[2:]))
    nearest = np.minimum(step[:-1], step[1:])
    neighbours_agree = (neighbour_gap <= tolerance_ns) | (
        outside & (nearest > GAP_SPIKE_RATIO * neighbour_gap + tolerance_ns))
    mask[1:-1] = far_before & far_after & neighbours_agree
    # At the ends one neighbour must do: far from it, and far beyond the usual spacing
    # (a 1 Hz heartbeat's first gap of 1.05 s is no spike).
    mask[0] = step[0] > max(tolerance_ns, END_SPIKE_RATIO * step[1])
    mask[-1] = step[-1] > max(tolerance_ns, END_SPIKE_RATIO * step[-2])
    return mask


def robust_span(times_ns: np.ndarray) -> tuple[int | None, int | None]:
    """First and last time, ignoring spikes (for a log's span in `inspect`)."""
    times = np.asarray(times_ns, dtype=np.int64)
    kept = times[~spikes(times)]
    if kept.size == 0:
        return None, None
    return int(kept.min()), int(kept.max())
