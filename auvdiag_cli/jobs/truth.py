"""The ground truth beside a log, ``NAME.truth.csv`` (true quantities over time, as the
simulator writes it and a test rig may too), laid against a diagnosis once the engine is
done: how far the substituted signal and the failed sensor lie from the true signal, and the
true track. The diagnosis itself never reads it."""

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.diagnosis import diagnose
from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.engine.substitution import Track, rms
from auvdiag_cli.simulator.truth_files import truth_paths
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

TRUE_TRACK_COLUMNS = ["x_m", "y_m"]


def truth_series(log_path: Path, columns: list[str], time_s: np.ndarray
                 ) -> dict[str, np.ndarray] | None:
    """The named truth columns interpolated at ``time_s``; None when the log has no truth
    or lacks a column."""
    csv_path = truth_paths(log_path)[1]
    if not csv_path.is_file():
        return None
    import pandas as pd  # only the simulator's own logs have a truth table

    table = pd.read_csv(csv_path)
    if "t_s" not in table or any(column not in table for column in columns):
        return None
    t = table["t_s"].to_numpy(dtype=float)
    return {c: np.interp(time_s, t, table[c].to_numpy(dtype=float)) for c in columns}


def compare_with_truth(diagnosis: Diagnosis, profile: Profile) -> Diagnosis:
    """The diagnosis with its substitution's truth figures, where the log has ground truth
    beside it."""
    substitution, matching = diagnosis.substitution, diagnosis.histories.matching
    if substitution is None or matching is None:
        return diagnosis
    sensor = profile.sensor(substitution.signal)
    if sensor.truth_column is None:
        return diagnosis
    time_s = diagnosis.histories.time_s
    truth = truth_series(diagnosis.log, [sensor.truth_column, *TRUE_TRACK_COLUMNS], time_s)
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


def diagnose_with_truth(path: Path, profile: Profile, model: LoadedModel,
                        companions: Sequence[Path] = (), mission: Path | None = None
                        ) -> Diagnosis:
    """The diagnosis of ``path``, and where the log has ground truth beside it, the
    substitution laid against it (what the CLI, an audit and the library report)."""
    return compare_with_truth(diagnose(path, profile, model, companions, mission), profile)
