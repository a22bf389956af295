"""`auvdiag calibrate`: thresholds from the g the model reaches on normal logs.

For each diagnosis mode (mission, and each DMS) and signal, the threshold is the largest g
seen on the normal logs times a margin. On those logs that gives zero false alarms by
construction; the false-alarm rate it implies elsewhere is stated as the rule-of-three
upper bound (no event in T hours: fewer than 3/T per hour at 95 % confidence). Faulty logs,
when given, are diagnosed with the new thresholds to show the detection margin.
"""

from collections.abc import Sequence
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.diagnosis import Diagnosis, diagnose_ingested
from auvdiag_cli.errors import UsageError
from auvdiag_cli.ingest import ingest
from auvdiag_cli.numeric import peak
from auvdiag_cli.profile import MISSION_MODE, Profile
from auvdiag_cli.report_json import write_json
from models.store import METADATA_FILE, LoadedModel

MIN_SAMPLES_PER_MODE = 300     # 30 s at 10 Hz: fewer and the profile's threshold is kept


@dataclass(frozen=True)
class ModeCalibration:
    mode: str
    samples: int
    hours: float
    max_g: dict[str, float]
    thresholds: dict[str, float]
    kept_default: bool


@dataclass(frozen=True)
class FaultyCheck:
    log: str
    verdict: str
    component: str | None
    candidates: list[str]
    peak_ratio: float     # the largest g / threshold anywhere in the log


@dataclass(frozen=True)
class CalibrationResult:
    margin: float
    modes: list[ModeCalibration]
    thresholds: dict[str, dict[str, float]]
    normal_hours: float
    false_alarm_bound_per_hour: float
    faulty: list[FaultyCheck]


def _mode_key(segment_name: str) -> str:
    return MISSION_MODE if segment_name == "MISSION" else segment_name


def _g_by_mode(diagnosis: Diagnosis) -> dict[str, np.ndarray]:
    assert diagnosis.matching is not None
    result: dict[str, list[np.ndarray]] = {}
    for segment in diagnosis.segments:
        inside = ((diagnosis.time_s >= segment.segment.start_s)
                  & (diagnosis.time_s <= segment.segment.end_s))
        result.setdefault(_mode_key(segment.segment.name), []).append(
            diagnosis.matching.g_percent[inside])
    return {mode: np.concatenate(parts) for mode, parts in result.items()}


def calibrate(model: LoadedModel, profile: Profile, normal_logs: Sequence[Path],
              faulty_logs: Sequence[Path] = (), margin: float = 1.5,
              floor_at_profile: bool = False) -> CalibrationResult:
    """Derive thresholds; the model object's metadata is updated (not yet written).
    ``floor_at_profile``: never below the profile's threshold for the mode (a signal a
    sequence hardly moves has a tiny normal g, and a threshold of 1.5 times noise would
    trip on the next dive's noise)."""
    if margin < 1.0:
        raise UsageError("--margin below 1 would raise alarms on the calibration logs")
    # Judge the calibration logs without any earlier calibration: raw g is what counts.
    base = replace(model, metadata={**model.metadata, "thresholds": profile.thresholds})
    samples: dict[str, list[np.ndarray]] = {}
    for path in normal_logs:
        diagnosis = diagnose_ingested(ingest(path, profile), profile, base)
        for mode, g in _g_by_mode(diagnosis).items():
            samples.setdefault(mode, []).append(g)
    thresholds = {mode: dict(values) for mode, values in profile.thresholds.items()}
    modes = []
    dt_h = profile.dt_s / 3600
    for mode, parts in sorted(samples.items()):
        g = np.concatenate(parts)
        finite = np.isfinite(g).all(axis=1)
        count = int(finite.sum())
        peaks = {name: peak(g[:, i]) for i, name in enumerate(profile.sensor_names)}
        keep = count < MIN_SAMPLES_PER_MODE or mode not in (*profile.dms, MISSION_MODE)
        if not keep:
            floor = profile.thresholds_for(mode) if floor_at_profile else {}
            thresholds[mode] = {name: round(max(margin * peak, floor.get(name, 0.0)), 2)
                                for name, peak in peaks.items()}
        modes.append(ModeCalibration(mode, count, count * dt_h,
                                     {k: round(v, 3) for k, v in peaks.items()},
                                     thresholds.get(mode, profile.thresholds_for(mode)), keep))
    hours = sum(m.hours for m in modes)
    if hours == 0:
        raise UsageError("no usable normal data in the calibration logs")
    model.metadata["thresholds"] = thresholds
    calibrated = replace(model, metadata=model.metadata)
    checks = []
    for path in faulty_logs:
        d = diagnose_ingested(ingest(path, profile), profile, calibrated)
        ratio = peak(d.matching.g_percent / d.thresholds) if d.matching else 0.0
        checks.append(FaultyCheck(str(path), d.verdict, d.component, d.candidates,
                                  round(ratio, 2)))
    result = CalibrationResult(margin, modes, thresholds, hours, 3.0 / hours, checks)
    model.metadata["calibration"] = _record(result, normal_logs, floor_at_profile)
    return result


def _record(result: CalibrationResult, normal_logs: Sequence[Path], floor_at_profile: bool
            ) -> dict[str, Any]:
    return {
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "method": "threshold = margin x largest g on the normal logs, per mode and signal",
        "margin": result.margin,
        "floor_at_profile": floor_at_profile,
        "normal_logs": [p.name for p in normal_logs],
        "normal_hours": round(result.normal_hours, 4),
        "false_alarms_on_normal_logs": 0,
        "false_alarm_rate_upper_95_per_hour": round(result.false_alarm_bound_per_hour, 3),
        "modes": [{"mode": m.mode, "samples": m.samples, "max_g": m.max_g,
                   "thresholds": m.thresholds, "kept_profile_default": m.kept_default}
                  for m in result.modes],
        "faulty_logs": [c.__dict__ for c in result.faulty],
    }


def write_metadata(model: LoadedModel, directory: Path) -> None:
    """Write the (re)calibrated metadata; a copy target gets the weights too."""
    source = Path(model.path)
    if directory.resolve() != source.resolve():
        directory.mkdir(parents=True, exist_ok=True)
        for file in source.iterdir():
            if file.name != METADATA_FILE:
                (directory / file.name).write_bytes(file.read_bytes())
    write_json(model.metadata, directory / METADATA_FILE)
