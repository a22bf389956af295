"""The time histories behind a verdict, on the model grid."""

from dataclasses import dataclass, field

import numpy as np

from auvdiag_cli.engine.residuals import Matching


@dataclass(frozen=True)
class Histories:
    """The time histories behind a verdict, on the model grid: what the reports plot and
    calibration measures; the verdict itself never needs them."""

    time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    commands: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    command_names: tuple[str, ...] = ()
    sensor_names: tuple[str, ...] = ()
    matching: Matching | None = None          # SS, SM and g
    thresholds: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    b_series: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    # What the change test judged: the moment-ahead predictor's error where the model has
    # one, else the replay's (`engine.change_check.change_residual`).
    change_residual: np.ndarray | None = None
    change_names: tuple[str, ...] = ()        # its columns: the sensors, then the loops

    @property
    def duration_s(self) -> float | None:
        return float(self.time_s[-1]) if self.time_s.size else None
