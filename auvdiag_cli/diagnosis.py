"""The diagnosis engine: one log in, one `Diagnosis` out. Rendering never recomputes."""

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.detection import binary_vector, detect, look_up
from auvdiag_cli.errors import ModelError
from auvdiag_cli.ingest import IngestedLog, ingest
from auvdiag_cli.matching import Matching, match
from auvdiag_cli.profile import Profile
from auvdiag_cli.segments import Segment, segments_from_markers, threshold_matrix
from models.store import LoadedModel

ONSET_LOOKBACK_S = 300.0
PAPER_ASSUMPTIONS = (
    "The environment is steady: a change in how the vehicle moves comes only from its hardware.",
    "At most one sensor or actuator is defective at a time.",
    "A component is either normal or totally defective.",
    "Once defective, a component stays defective until the diagnosis ends.",
)


@dataclass
class SegmentResult:
    segment: Segment
    max_g: dict[str, float]
    b: dict[str, int]


@dataclass
class Substitution:
    """Substituting Control for a failed sensor: SM_i replaces SS_i from ``from_s`` on."""

    signal: str
    from_s: float
    expected_error_rms: float | None   # the model's free-run error on held-out normal logs
    unit: str


@dataclass
class Diagnosis:
    log: Path
    format: str
    vehicle: str
    verdict: str                      # normal | fault | undetermined
    component: str | None
    candidates: list[str]
    case: int | None
    b: dict[str, int]
    detected_at_s: float | None
    onset_s: float | None
    segments: list[SegmentResult]
    substitution: Substitution | None
    model: dict[str, Any]
    window_samples: int
    decision_window_s: float
    sensor_units: dict[str, str]
    notes: list[str] = field(default_factory=list)
    # Time histories for reports.
    time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    commands: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    command_names: tuple[str, ...] = ()
    sensor_names: tuple[str, ...] = ()
    matching: Matching | None = None
    thresholds: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    b_series: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))


def check_model_fits(model: LoadedModel, profile: Profile, log: Path) -> None:
    """Refuse a model trained for other signals or another step than the profile's."""
    meta = model.metadata
    if model.command_names != profile.command_names or model.sensor_names != profile.sensor_names:
        raise ModelError(
            f"{log}: model {model.path} expects commands {list(model.command_names)} and sensors "
            f"{list(model.sensor_names)}, profile {profile.name!r} gives "
            f"{list(profile.command_names)} and {list(profile.sensor_names)}")
    if abs(float(meta.get("dt_s", -1.0)) - profile.dt_s) > 1e-9:
        raise ModelError(f"{log}: model step {meta.get('dt_s')} s differs from the profile's "
                         f"{profile.dt_s} s")


def diagnose(path: Path, profile: Profile, model: LoadedModel) -> Diagnosis:
    """Diagnose the log at ``path`` (raises LogError / ModelError when it cannot)."""
    check_model_fits(model, profile, path)
    return diagnose_ingested(ingest(path, profile), profile, model)


def diagnose_ingested(log: IngestedLog, profile: Profile, model: LoadedModel) -> Diagnosis:
    frame, signals = log.frame, log.signals
    full_scale = model.metadata.get("full_scale", profile.full_scales)
    window = int(model.metadata.get("window_samples", profile.window_samples))
    matching = match(model, frame, full_scale, window)
    segments = segments_from_markers(signals.markers, signals.start_ns, float(frame.time_s[-1]),
                                     _with_model_thresholds(profile, model))
    thresholds = threshold_matrix(segments, frame.time_s, frame.sensor_names)
    b_series = binary_vector(matching.g_percent, thresholds)
    scales = np.asarray([full_scale[n] for n in frame.sensor_names])
    residual = np.abs(matching.measured - matching.modelled) / scales
    detection = detect(b_series, residual, thresholds, frame.sensor_names,
                       round(profile.decision_window_s / profile.dt_s),
                       round(ONSET_LOOKBACK_S / profile.dt_s))
    notes = list(signals.notes) + frame.notes
    notes += [f"gap in {gap.signal} from {gap.start_s:.1f} s to {gap.end_s:.1f} s "
              "(not interpolated)" for gap in frame.gaps]
    diagnosis = Diagnosis(
        log=signals.path, format=signals.format, vehicle=profile.name, verdict="normal",
        component=None, candidates=[], case=_normal_case(profile),
        b={name: 0 for name in frame.sensor_names}, detected_at_s=None, onset_s=None,
        segments=_segment_results(segments, frame.time_s, matching, b_series,
                                  frame.sensor_names),
        substitution=None, model=model.identity, window_samples=window,
        decision_window_s=profile.decision_window_s,
        sensor_units={s.name: s.unit for s in profile.sensors}, notes=notes,
        time_s=frame.time_s, commands=frame.commands, command_names=frame.command_names,
        sensor_names=frame.sensor_names, matching=matching, thresholds=thresholds,
        b_series=b_series)
    if detection is not None:
        _apply_detection(diagnosis, detection.b, frame.time_s[detection.alarm_index],
                         frame.time_s[detection.onset_index], profile, model)
    return diagnosis


def _with_model_thresholds(profile: Profile, model: LoadedModel) -> Profile:
    """Thresholds calibrated into the model override the profile's defaults."""
    calibrated = model.metadata.get("thresholds")
    if not calibrated:
        return profile
    return replace(profile, thresholds={**profile.thresholds, **calibrated})


def _normal_case(profile: Profile) -> int | None:
    row = look_up(profile.pattern, {s.name: 0 for s in profile.sensors})
    return None if row is None else row.case


def _apply_detection(diagnosis: Diagnosis, b: dict[str, int], alarm_s: float, onset_s: float,
                     profile: Profile, model: LoadedModel) -> None:
    diagnosis.verdict = "fault"
    diagnosis.b = b
    diagnosis.detected_at_s = round(float(alarm_s), 3)
    diagnosis.onset_s = round(float(onset_s), 3)
    row = look_up(profile.pattern, b)
    if row is None:
        diagnosis.case = None
        diagnosis.notes.append(f"b = {b} fits no row of the pattern table: more than one fault, "
                               "or one the table does not describe")
        return
    diagnosis.case = row.case
    diagnosis.candidates = list(row.components)
    if len(row.components) == 1:
        diagnosis.component = row.components[0]
        sensor = next((s for s in profile.sensors if s.component == diagnosis.component), None)
        if sensor is not None:
            errors = model.metadata.get("heldout_error", {}).get("rms", {})
            diagnosis.substitution = Substitution(sensor.name, diagnosis.onset_s,
                                                  errors.get(sensor.name), sensor.unit)


def _segment_results(segments: list[Segment], time_s: np.ndarray, matching: Matching,
                     b_series: np.ndarray, sensor_names: tuple[str, ...]) -> list[SegmentResult]:
    results = []
    for segment in segments:
        inside = (time_s >= segment.start_s) & (time_s <= segment.end_s)
        g = matching.g_percent[inside]
        max_g = {name: (round(float(np.nanmax(g[:, i])), 3)
                        if g.size and np.isfinite(g[:, i]).any() else float("nan"))
                 for i, name in enumerate(sensor_names)}
        b = {name: int(b_series[inside, i].any()) for i, name in enumerate(sensor_names)}
        results.append(SegmentResult(segment, max_g, b))
    return results
