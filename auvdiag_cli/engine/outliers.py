"""Isolated spikes in the sensors: found, kept out of g and of the replay's start states,
and reported.

A sample is a spike when it stands further from the median of its 7 neighbours than both
8 robust standard deviations of that signal's local scatter and a tenth of its full scale.
The median window sees through up to three bad samples in a row, while a real step (a
sensor that dies and stays dead, a commanded change) moves the median with it and is kept.
A run of such samples is a spike only when it is isolated: entered and left by jumps
larger than `ISOLATION` times the change of the samples just outside it. On a smooth signal
the local scatter is near zero (on a monotone stretch every sample is its neighbours'
median), so the top of a fast but smooth excursion (a yaw rate swinging as a rudder
sticks) stands out of its median; it is reached by the signal's own motion and kept.
"""

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

SPIKE_WINDOW = 7          # samples: the neighbourhood a spike stands out from
SCALE_WINDOW = 31         # samples: the local scatter's neighbourhood
SPIKE_SIGMAS = 8.0
SPIKE_FLOOR = 0.1         # of the signal's full scale
MAD_TO_SIGMA = 1.4826
ISOLATION = 2.0          # a spike's jumps against the change beside it (a swing's are alike)


def centred_median(values: np.ndarray, window: int, min_periods: int,
                   rows: np.ndarray | None = None) -> np.ndarray:
    """The median of the finite values in a centred window of ``window`` samples (NaN where
    it holds fewer than ``min_periods``; the middle two averaged for an even count), as
    pandas' rolling(window, center=True, min_periods).median() gives it; at ``rows`` only
    when given."""
    after = (window - 1) // 2
    padded = np.concatenate((np.full(window - 1 - after, np.nan), values, np.full(after, np.nan)))
    windows = sliding_window_view(padded, window)
    finite = np.concatenate(([0], np.cumsum(np.isfinite(padded))))
    count = finite[window:] - finite[:-window]
    if rows is not None:
        windows, count = windows[rows], count[rows]
    ordered = np.sort(windows, axis=1).ravel()                          # NaN sorts last
    first = np.arange(0, ordered.size, window)
    low, high = np.maximum(count - 1, 0) // 2, np.minimum(np.maximum(count, 1) // 2, window - 1)
    median = 0.5 * (ordered[first + low] + ordered[first + high])
    return np.where(count >= min_periods, median, np.nan)


def spike_mask(values: np.ndarray, full_scale: float) -> np.ndarray:
    departure = np.abs(values - centred_median(values, SPIKE_WINDOW, 3))
    # Only a sample further out than the floor can be a spike: the local scatter is worked
    # out for those alone (the wider median is most of the cost).
    with np.errstate(invalid="ignore"):
        candidates = np.flatnonzero(departure > SPIKE_FLOOR * full_scale)
    many = 4 * candidates.size > values.size       # then one pass over all is cheaper
    scatter = MAD_TO_SIGMA * centred_median(departure, SCALE_WINDOW, 5,
                                            None if many else candidates)
    if many:
        scatter = scatter[candidates]
    spikes = np.zeros(values.size, bool)
    with np.errstate(invalid="ignore"):
        spikes[candidates] = departure[candidates] > SPIKE_SIGMAS * scatter
    return _isolated(values, spikes)


def _isolated(values: np.ndarray, outlying: np.ndarray) -> np.ndarray:
    """``outlying`` less the runs that the signal reaches by its own motion: a run is kept
    where the jump into it and the jump out of it both exceed `ISOLATION` times the change
    between the two samples outside it on that side (a side without those samples holds)."""
    padded = np.concatenate(([False], outlying, [False]))
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    firsts, lasts = edges[0::2], edges[1::2] - 1

    def jump(i: np.ndarray, j: np.ndarray) -> np.ndarray:
        inside = (i >= 0) & (j < values.size)
        out = np.full(i.size, np.nan)
        out[inside] = np.abs(values[j[inside]] - values[i[inside]])
        return out

    into, before = jump(firsts - 1, firsts), jump(firsts - 2, firsts - 1)
    out_of, after = jump(lasts, lasts + 1), jump(lasts + 1, lasts + 2)
    with np.errstate(invalid="ignore"):
        reached = (into <= ISOLATION * before) | (out_of <= ISOLATION * after)
    kept = outlying.copy()
    for first, last in zip(firsts[reached], lasts[reached], strict=True):
        kept[first:last + 1] = False
    return kept


def remove_spikes(sensors: np.ndarray, time_s: np.ndarray, names: tuple[str, ...],
                  full_scales: dict[str, float]) -> list[str]:
    """Set every isolated spike to NaN (in place); one note per signal that had any."""
    notes = []
    for column, name in enumerate(names):
        spikes = spike_mask(sensors[:, column], full_scales[name])
        if spikes.any():
            sensors[spikes, column] = np.nan
            first = float(time_s[np.flatnonzero(spikes)[0]])
            notes.append(f"{int(spikes.sum())} isolated spike(s) in {name} left out of g and "
                         f"of the replay's start states (first at {first:.1f} s)")
    return notes
