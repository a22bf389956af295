"""Diagnosis segments of a log: DMS runs and mission, from the logged segment markers."""

from dataclasses import dataclass

import numpy as np

from adapters.signals import SegmentMarker
from auvdiag_cli.profile import MISSION_MODE, Profile

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
