"""Ground truth beside a log: ``NAME.truth.json`` (what happened) and ``NAME.truth.csv``
(true quantities over time), as the simulator writes them and a test rig may too."""

from pathlib import Path

import numpy as np
import pandas as pd


def truth_paths(log_path: Path) -> tuple[Path, Path]:
    """Where the ground truth of a log lives: ``NAME.truth.json`` and ``NAME.truth.csv``."""
    stem = log_path.name.split(".")[0]
    return (log_path.with_name(stem + ".truth.json"), log_path.with_name(stem + ".truth.csv"))


def truth_series(log_path: Path, columns: list[str], time_s: np.ndarray
                 ) -> dict[str, np.ndarray] | None:
    """The named truth columns interpolated at ``time_s``; None when the log has no truth
    or lacks a column."""
    csv_path = truth_paths(log_path)[1]
    if not csv_path.is_file():
        return None
    table = pd.read_csv(csv_path)
    if "t_s" not in table or any(column not in table for column in columns):
        return None
    t = table["t_s"].to_numpy(dtype=float)
    return {c: np.interp(time_s, t, table[c].to_numpy(dtype=float)) for c in columns}
