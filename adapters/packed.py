"""Numbers at many byte offsets of one buffer, read in one NumPy operation."""

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def gather_words(data: np.ndarray, starts: np.ndarray, dtype: str) -> np.ndarray:
    """The number of type ``dtype`` stored at each of ``starts`` (each must fit the data)."""
    width = np.dtype(dtype).itemsize
    if starts.size == 0:
        return np.zeros(0, dtype)
    return np.ascontiguousarray(sliding_window_view(data, width)[starts]).view(dtype)[:, 0]


def gathered(data: np.ndarray, starts: np.ndarray, ends: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """The slices ``data[starts[i]:ends[i]]`` back to back, and where each begins there."""
    if starts.size and (starts[1:] == ends[:-1]).all():
        # Stored back to back already (a database's blobs joined): one slice, no copy.
        return data[starts[0]:ends[-1]], starts - starts[0]
    lengths = ends - starts
    begins = np.zeros(lengths.size, np.int64)
    np.cumsum(lengths[:-1], out=begins[1:])
    if lengths.size and (lengths == lengths[0]).all() and lengths[0] > 0:
        # Messages of one size (the usual case): whole rows of a strided view, not bytes.
        return sliding_window_view(data, int(lengths[0]))[starts].ravel(), begins
    positions = np.repeat(starts - begins, lengths) + np.arange(int(lengths.sum()))
    return data[positions], begins
