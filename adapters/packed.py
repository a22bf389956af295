"""Numbers at many byte offsets of one buffer, read in one NumPy operation."""

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def gather_words(data: np.ndarray, starts: np.ndarray, dtype: str) -> np.ndarray:
    """The number of type ``dtype`` stored at each of ``starts`` (each must fit the data)."""
    width = np.dtype(dtype).itemsize
    if starts.size == 0:
        return np.zeros(0, dtype)
    return np.ascontiguousarray(sliding_window_view(data, width)[starts]).view(dtype)[:, 0]
