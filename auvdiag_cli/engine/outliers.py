"""Isolated spikes in the sensors: found, kept out of g and of the replay's start states,
and reported.

A sample is a spike when it stands further from the median of its 7 neighbours than both
8 robust standard deviations of that signal's local scatter and a tenth of its full scale.
The median window sees through up to three bad samples in a row, while a real step (a
sensor that dies and stays dead, a commanded change) moves the median with it and is kept.
"""

import numpy as np
import pandas as pd

SPIKE_WINDOW = 7          # samples: the neighbourhood a spike stands out from
SCALE_WINDOW = 31         # samples: the local scatter's neighbourhood
SPIKE_SIGMAS = 8.0
SPIKE_FLOOR = 0.1         # of the signal's full scale
MAD_TO_SIGMA = 1.4826


def spike_mask(values: np.ndarray, full_scale: float) -> np.ndarray:
    series = pd.Series(values)
    median = series.rolling(SPIKE_WINDOW, center=True, min_periods=3).median()
    departure = (series - median).abs()
    scatter = MAD_TO_SIGMA * departure.rolling(SCALE_WINDOW, center=True, min_periods=5).median()
    limit = np.maximum(SPIKE_SIGMAS * scatter.to_numpy(), SPIKE_FLOOR * full_scale)
    return np.asarray(departure.to_numpy() > limit)


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
