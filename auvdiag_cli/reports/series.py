"""The time histories a report plots, kept beside the JSON report as an .npz file so that
`auvdiag report` can draw the same PDF later without the log or the model. Only plain
arrays are stored (numbers and strings): loading never unpickles anything."""

import zipfile
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.results import Diagnosis
from auvdiag_errors import UsageError

Series = dict[str, np.ndarray]
SERIES_SUFFIX = ".series.npz"


def series_from_diagnosis(diagnosis: Diagnosis) -> Series:
    d = diagnosis
    series: Series = {
        "time_s": d.histories.time_s,
        # The log's own clock: time_s counts from here (the MCAP export needs it).
        "start_ns": np.asarray(d.start_ns, dtype=np.int64),
        "command_names": np.asarray(d.histories.command_names, dtype=str),
        "commands": d.histories.commands.astype(np.float32),
        "sensor_names": np.asarray(d.histories.sensor_names, dtype=str),
        "thresholds": d.histories.thresholds.astype(np.float32),
        "b": d.histories.b_series.astype(np.int8),
    }
    if d.histories.matching is not None:
        series["measured"] = d.histories.matching.measured.astype(np.float32)
        series["modelled"] = d.histories.matching.modelled.astype(np.float32)
        series["g_percent"] = d.histories.matching.g_percent.astype(np.float32)
    if d.healthy_from_onset is not None:
        series["healthy_from_onset"] = d.healthy_from_onset.astype(np.float32)
    change = d.change_check
    if change is not None and change.ratios is not None and change.ratio_names:
        series["change_names"] = np.asarray(change.ratio_names, dtype=str)
        series["change_ratio"] = change.ratios.astype(np.float32)
    if d.effort_check is not None:
        series.update(effort_series(d.effort_check))
    waypoints = [point for leg in d.mission_legs for point in leg.waypoints]
    if waypoints:
        series["waypoints_m"] = np.asarray(waypoints, dtype=np.float64)
    substitution = d.substitution
    if substitution is not None:
        series["substituted"] = substitution.substituted.astype(np.float32)
        if substitution.truth is not None:
            series["substituted_truth"] = substitution.truth.astype(np.float32)
        for name, track in substitution.tracks.items():
            series[f"track_{name}_m"] = np.column_stack([track.x_m, track.y_m])
        loop = substitution.closed_loop
        if loop is not None:
            series["closed_loop_time_s"] = loop.time_s
            series["closed_loop_m"] = np.column_stack([loop.x_m, loop.y_m])
    return series


def effort_series(check: EffortCheck) -> Series:
    """Each judged group's window shares, normal shares and band, keyed by group number."""
    series: Series = {"effort_groups": np.asarray([g.group for g in check.series], dtype=str)}
    for k, group in enumerate(check.series):
        series[f"effort_{k}_members"] = np.asarray(group.members, dtype=str)
        series[f"effort_{k}_time_s"] = group.time_s
        series[f"effort_{k}_shares"] = group.shares.astype(np.float32)
        series[f"effort_{k}_normal"] = group.normal.astype(np.float32)
        series[f"effort_{k}_band"] = group.band.astype(np.float32)
    return series


def series_path(json_path: Path) -> Path:
    """report.json → report.series.npz"""
    return json_path.with_name(json_path.stem + SERIES_SUFFIX)


def save_series(series: Series, target: Path) -> None:
    """Write atomically, like the JSON beside it."""
    temporary = target.with_name(f".{target.name}.tmp.npz")
    np.savez_compressed(temporary, **series)  # type: ignore[arg-type]
    temporary.replace(target)


def load_series(source: Path) -> Series:
    try:
        with np.load(source, allow_pickle=False) as archive:
            return {name: archive[name] for name in archive.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise UsageError(f"{source}: unreadable time histories: {error}") from None
