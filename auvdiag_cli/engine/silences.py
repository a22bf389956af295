"""Long stretches with nothing to judge are left off the model grid, so that a log costs
what its samples cost and not what its clock spans: a recorder paused for hours, a clock
that jumped, an hour on deck disarmed.

Two kinds are skipped, each only when longer than LONG_S, and each keeping its first and
last EDGE_S on the grid (detection windows, onset look-backs and plots still see it begin
and end; the replay restarts after it as after any gap):

- silences: no signal at all has a sample (found from each signal's own gaps, before the
  grid exists, so memory follows the samples too);
- blind stretches: the grid steps where no sensor may be judged (a command gap, or the
  vehicle not operating).

Grid points stay on the lattice first_ns + k·Δt, so a log without such stretches gets the
same grid as before."""

from collections.abc import Iterable, Sequence

import numpy as np

LONG_S = 300.0           # a stretch longer than this is skipped …
EDGE_S = 60.0            # … all but this much at each end
NS_PER_S = 1_000_000_000

Interval = tuple[int, int]      # (start_ns, end_ns), exclusive at both ends


def _long_gaps(times_ns: np.ndarray, long_ns: int) -> list[Interval]:
    steps = np.diff(times_ns)
    return [(int(times_ns[i]), int(times_ns[i + 1])) for i in np.flatnonzero(steps > long_ns)]


def _intersect(a: Sequence[Interval], b: Sequence[Interval]) -> list[Interval]:
    """The intervals both sorted, disjoint lists cover."""
    both, i, j = [], 0, 0
    while i < len(a) and j < len(b):
        start, end = max(a[i][0], b[j][0]), min(a[i][1], b[j][1])
        if start < end:
            both.append((start, end))
        if a[i][1] < b[j][1]:
            i += 1
        else:
            j += 1
    return both


def silences(series_times: Iterable[np.ndarray], long_s: float = LONG_S) -> list[Interval]:
    """Where no signal has a sample for longer than ``long_s`` (each signal's times sorted)."""
    long_ns = round(long_s * NS_PER_S)
    common: list[Interval] | None = None
    for times_ns in series_times:
        gaps = _long_gaps(times_ns, long_ns)
        common = gaps if common is None else _intersect(common, gaps)
        if not common:
            return []
    return [(s, e) for s, e in common or [] if e - s > long_ns]


def lattice_spans(first_ns: int, last_ns: int, dt_ns: int, skipped: Sequence[Interval],
                  edge_s: float = EDGE_S) -> list[tuple[int, int]]:
    """Runs [start, stop) of lattice steps k (grid time first_ns + k·dt_ns, up to last_ns)
    outside the inner part of each skipped interval (its first and last ``edge_s`` stay)."""
    edge_ns = round(edge_s * NS_PER_S)
    count = (last_ns - first_ns) // dt_ns + 1
    spans, start = [], 0
    for begin_ns, end_ns in skipped:
        cut = -(-(begin_ns + edge_ns - first_ns) // dt_ns)       # first step dropped
        resume = (end_ns - edge_ns - first_ns) // dt_ns + 1      # first step kept again
        if cut < resume and start < count:
            spans.append((start, min(cut, count)))
            start = max(start, resume)
    spans.append((start, count))
    return [(a, b) for a, b in spans if a < b]


def kept_steps(blind: np.ndarray, grid_ns: np.ndarray, long_s: float = LONG_S,
               edge_s: float = EDGE_S) -> np.ndarray:
    """Which grid steps to keep: all but the inner part of each blind run longer than
    ``long_s`` (its first and last ``edge_s`` stay)."""
    keep = np.ones(blind.size, bool)
    long_ns, edge_ns = round(long_s * NS_PER_S), round(edge_s * NS_PER_S)
    changes = np.flatnonzero(np.diff(np.concatenate(([0], blind.astype(np.int8), [0]))))
    for start, end in zip(changes[::2], changes[1::2], strict=True):
        first_ns, last_ns = int(grid_ns[start]), int(grid_ns[end - 1])
        if last_ns - first_ns > long_ns:
            run = grid_ns[start:end]
            keep[start:end] = (run < first_ns + edge_ns) | (run > last_ns - edge_ns)
    return keep
