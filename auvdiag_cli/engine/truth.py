"""Files beside a log: ground truth, ``NAME.truth.json`` (what happened) and
``NAME.truth.csv`` (true quantities over time), and the mission plan, ``NAME.mission.json``,
as the simulator writes them and a test rig or mission planner may too."""

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd


def truth_paths(log_path: Path) -> tuple[Path, Path]:
    """Where the ground truth of a log lives: ``NAME.truth.json`` and ``NAME.truth.csv``."""
    stem = log_path.name.split(".")[0]
    return (log_path.with_name(stem + ".truth.json"), log_path.with_name(stem + ".truth.csv"))


def mission_path(log_path: Path) -> Path:
    return log_path.with_name(log_path.name.split(".")[0] + ".mission.json")


def read_missions(path: Path) -> list[dict[str, Any]]:
    """Mission legs: ``start_s`` (from the log's first message), ``waypoints`` [[x, y], …]
    in metres in the vehicle's navigation frame (origin and heading at the leg's start),
    and optionally ``cruise_speed_mps``."""
    data = json.loads(path.read_text(encoding="utf-8"))
    legs = data.get("missions") if isinstance(data, dict) else None
    if not isinstance(legs, list) or not all(
            isinstance(leg, dict) and "start_s" in leg and "waypoints" in leg for leg in legs):
        raise ValueError(f"{path}: expected {{\"missions\": [{{\"start_s\": …, "
                         "\"waypoints\": [[x, y], …]}, …]}")
    return legs


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
