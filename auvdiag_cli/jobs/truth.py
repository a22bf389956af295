"""A log's ground truth, a CSV of true quantities over time (``NAME.truth.csv``, as the
simulator writes it beside its logs and a test rig may too), laid against a diagnosis when
the caller gives one (`auvdiag diagnose --truth`): how far the substituted signal and the
failed sensor lie from the true signal, and the true track. The diagnosis itself never
looks for it."""

from dataclasses import replace
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.engine.substitution import Track, rms
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import LogError

TRUE_TRACK_COLUMNS = ["x_m", "y_m"]


def truth_series(csv_path: Path, columns: list[str], time_s: np.ndarray
                 ) -> dict[str, np.ndarray] | None:
    """The named truth columns interpolated at ``time_s``; None when the table lacks its
    clock ``t_s`` or a column. Raises LogError when the file cannot be read."""
    import pandas as pd  # only simulated logs and test rigs have a truth table

    try:
        table = pd.read_csv(csv_path)
    except (OSError, ValueError) as error:
        raise LogError(csv_path, f"not a ground-truth table: {error}") from None
    if "t_s" not in table or any(column not in table for column in columns):
        return None
    t = table["t_s"].to_numpy(dtype=float)
    return {c: np.interp(time_s, t, table[c].to_numpy(dtype=float)) for c in columns}


def compare_with_truth(diagnosis: Diagnosis, profile: Profile, truth_csv: Path
                       ) -> Diagnosis:
    """The diagnosis with its substitution's truth figures, where ``truth_csv`` holds the
    substituted signal's true values (its profile `truth_column`)."""
    substitution, matching = diagnosis.substitution, diagnosis.histories.matching
    if substitution is None or matching is None:
        return diagnosis
    sensor = profile.sensor(substitution.signal)
    if sensor.truth_column is None:
        return diagnosis
    time_s = diagnosis.histories.time_s
    truth = truth_series(truth_csv, [sensor.truth_column, *TRUE_TRACK_COLUMNS], time_s)
    if truth is None:
        return diagnosis
    column = diagnosis.histories.sensor_names.index(sensor.name)
    after = time_s >= substitution.from_s
    true_signal = truth[sensor.truth_column]
    tracks = dict(substitution.tracks)
    if tracks:
        tracks["truth"] = Track(truth["x_m"], truth["y_m"])
    return replace(diagnosis, substitution=replace(
        substitution, truth=true_signal, tracks=tracks,
        truth_error_rms=rms(matching.modelled[after, column] - true_signal[after]),
        failed_error_rms=rms(matching.measured[after, column] - true_signal[after])))
