"""Reductions over residuals that may hold NaN (gaps, a replay restarted after them)."""

import numpy as np


def peak(values: np.ndarray) -> float:
    """The largest value, ignoring NaN; NaN when there is none (and no warning about it)."""
    flat = np.asarray(values, dtype=np.float64).ravel()
    return float(np.fmax.reduce(flat)) if flat.size else float("nan")
