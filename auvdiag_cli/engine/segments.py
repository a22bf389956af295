"""Diagnosis segments of a log: DMS runs and mission, from the logged segment markers or,
when a log has none, from the command history itself (each DMS is a fixed command history,
so it is found by matching the profile's template)."""

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from adapters.signals import SegmentMarker
from auvdiag_cli.vehicle.profile import MISSION_MODE, DiagnosisSequence, Profile

if TYPE_CHECKING:
    from auvdiag_cli.engine.ingest import IngestedLog

ROUTINE_MODE = "routine"


@dataclass(frozen=True)
class Segment:
    name: str            # DMS name (ZA, ZB, ZC) or MISSION
    mode: str            # "routine" (a DMS) or "mission"
    start_s: float
    end_s: float
    thresholds: dict[str, float]


def segments_from_markers(markers: list[SegmentMarker], start_ns: int, end_s: float,
                          profile: Profile) -> list[Segment]:
    """Cut the log at its markers; time before the first marker, or a log without markers,
    is treated as mission. A marker less than one model step after the previous cut
    relabels that segment (no segment is shorter than a step), and a repeated label
    continues the segment it repeats."""
    cuts: list[tuple[float, str]] = [(0.0, "MISSION")]
    for marker in sorted(markers, key=lambda m: m.time_ns):
        time_s = (marker.time_ns - start_ns) / 1e9
        label = marker.label.strip().upper()
        if time_s < cuts[-1][0] + profile.dt_s:
            cuts[-1] = (cuts[-1][0], label)
        elif label != cuts[-1][1]:
            cuts.append((time_s, label))
    segments = []
    for (start, label), (end, _) in zip(cuts, [*cuts[1:], (end_s, "")], strict=True):
        mode = ROUTINE_MODE if label in profile.dms else MISSION_MODE
        name = label if mode == ROUTINE_MODE else "MISSION"
        segments.append(Segment(name, mode, start, end, profile.thresholds_for(name)))
    return segments


def threshold_matrix(segments: list[Segment], time_s: np.ndarray,
                     sensor_names: tuple[str, ...]) -> np.ndarray:
    """t_i(k) for every sample: the thresholds of the segment each sample lies in."""
    thresholds = np.empty((len(time_s), len(sensor_names)))
    for segment in segments:
        inside = (time_s >= segment.start_s) & (time_s <= segment.end_s)
        thresholds[inside] = [segment.thresholds[name] for name in sensor_names]
    return thresholds


# A DMS matches where the commands follow its template within this much (normalised command;
# PWM logs quantise to 0.0025) on all but this fraction of samples (step edges may shift by
# a sample of receive jitter).
TEMPLATE_TOLERANCE = 0.02
TEMPLATE_MISMATCH = 0.05


def dms_template(dms: DiagnosisSequence, dt_s: float) -> np.ndarray:
    """The DMS command history on the model grid, shape (steps, n_commands)."""
    rows = [levels for duration, levels in dms.steps for _ in range(round(duration / dt_s))]
    return np.asarray(rows, dtype=np.float64)


def find_dms(commands: np.ndarray, profile: Profile) -> list[tuple[str, int, int]]:
    """(name, first index, end index) of every DMS run in the command history."""
    found: list[tuple[str, int, int]] = []
    for name, dms in profile.dms.items():
        template = dms_template(dms, profile.dt_s)
        length = len(template)
        at_first = np.all(np.abs(commands - template[0]) <= TEMPLATE_TOLERANCE, axis=1)
        starts = np.flatnonzero(at_first & ~np.concatenate(([False], at_first[:-1])))
        for start in starts:
            window = commands[start:start + length]
            if len(window) < length:
                continue
            off = np.any(np.abs(window - template) > TEMPLATE_TOLERANCE, axis=1)
            if off.mean() <= TEMPLATE_MISMATCH:
                found.append((name, int(start), int(start + length)))
    found.sort(key=lambda item: item[1])
    kept: list[tuple[str, int, int]] = []
    for item in found:
        if not kept or item[1] >= kept[-1][2]:
            kept.append(item)
    return kept


def segments_from_commands(commands: np.ndarray, time_s: np.ndarray, profile: Profile
                           ) -> list[Segment]:
    """DMS runs recognised in the commands; everything between them is mission."""
    segments: list[Segment] = []
    cursor = 0.0
    end_s = float(time_s[-1])
    for name, first, end in find_dms(commands, profile):
        start_s, stop_s = float(time_s[first]), float(time_s[min(end, len(time_s) - 1)])
        if start_s - cursor >= profile.dt_s:
            segments.append(Segment("MISSION", MISSION_MODE, cursor, start_s,
                                    profile.thresholds_for("MISSION")))
        segments.append(Segment(name, ROUTINE_MODE, start_s, stop_s,
                                profile.thresholds_for(name)))
        cursor = stop_s
    if end_s - cursor >= profile.dt_s or not segments:
        segments.append(Segment("MISSION", MISSION_MODE, cursor, end_s,
                                profile.thresholds_for("MISSION")))
    return segments


def segments_of(log: "IngestedLog", profile: Profile) -> list[Segment]:
    """The log's segments: from its markers when it has some, else from its commands."""
    signals, frame = log.signals, log.frame
    if signals.markers:
        return segments_from_markers(signals.markers, signals.start_ns,
                                     float(frame.time_s[-1]), profile)
    return segments_from_commands(frame.commands, frame.time_s, profile)


def mission_steps(segments: list[Segment], time_s: np.ndarray, operating: np.ndarray
                  ) -> np.ndarray:
    """True at the operating steps outside every DMS run (where the vehicle is driven in
    closed loop or by its pilot rather than by a fixed command history)."""
    steps = operating.copy() if len(operating) == len(time_s) else np.ones(len(time_s), bool)
    for segment in segments:
        if segment.mode == ROUTINE_MODE:
            steps &= ~((time_s >= segment.start_s) & (time_s <= segment.end_s))
    return steps
