"""One log's result in an audit, parsed once from the report the audit stored for it (or
its error) into typed values: what the table, the trend and the fleet PDF read."""

import math
from collections.abc import Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from auvdiag_cli.engine.coverage import Coverage
from auvdiag_cli.reports.report import Report, SegmentPart, SharePart

Document = Mapping[str, Any]     # a stored report as JSON gives it back


@dataclass(frozen=True)
class AuditRecord:
    log: str
    error: str | None = None
    verdict: str | None = None           # None: not analysed
    format: str | None = None
    vehicle: str | None = None           # the profile's vehicle
    fleet_vehicle: str = "."             # which vehicle of the fleet (the audit assigned)
    start_time_utc: str | None = None
    duration_s: float | None = None
    not_operating_s: float | None = None
    completeness: str | None = None      # "complete" or "partial" (analysed up to damage)
    not_judged: tuple[str, ...] = ()
    coverage: Coverage | None = None
    component: str | None = None
    candidates: tuple[str, ...] = ()
    case: int | None = None
    onset_s: float | None = None
    detected_at_s: float | None = None
    worst_g_ratio: float | None = None   # the largest g / threshold of a judged signal
    worst_g_signal: str | None = None
    segments: int = 0
    routine_segments: int = 0
    substituted_signal: str | None = None
    weakened_thrust_fraction: float | None = None
    driven_harder: tuple[str, ...] = ()
    worst_effort_ratio: float | None = None
    worst_effort_actuator: str | None = None
    # When the effort shares say a weakness began and when they saw it (None: no alarm
    # there); onset_s and detected_at_s are the verdict's, which another judge may set.
    effort_onset_s: float | None = None
    effort_detected_at_s: float | None = None
    recommended_dms: tuple[str, ...] = ()
    autopilot_alarms: tuple[str, ...] = ()   # trouble the vehicle's own software reported
    model: str | None = None             # the model's name
    model_path: str | None = None
    log_sha256: str | None = None
    result_file: str | None = None
    seconds: float | None = None
    bits: Mapping[str, int] = field(default_factory=dict)        # b, per signal
    margins: Mapping[str, float] = field(default_factory=dict)   # peak ratio to threshold

    @property
    def analysed(self) -> bool:
        return not self.error and self.verdict is not None

    @property
    def partly_judged(self) -> bool:
        """A NORMAL over less than every signal and actuator of the profile, or judged only
        from partway into the log."""
        return self.analysed and self.verdict == "normal" and self.coverage is not None \
            and not self.coverage.complete

    @property
    def damaged(self) -> bool:
        """Analysed only up to damage (salvaged)."""
        return not self.error and self.completeness == "partial"

    def describe(self) -> str:
        """The verdict and the component in a few words, or the error."""
        if self.error:
            return f"error: {self.error}"
        what = self.component or " or ".join(self.candidates)
        return (self.verdict or "?") + (f" ({what})" if what else "")

    @classmethod
    def from_report(cls, document: Document) -> "AuditRecord":
        """Parse a stored per-log record (a JSON report with the audit's stamp, or an
        error); a key a report from an older release lacks takes its empty value."""
        stamp = AuditStamp.from_json(document.get("audit"))
        log = str(document["log"])
        fleet_vehicle = stamp.vehicle or Path(log).parent.name or "."
        error = document.get("error")
        if error or "verdict" not in document:
            return cls(log=log, error=str(error or "no verdict in the stored report"),
                       fleet_vehicle=fleet_vehicle, log_sha256=stamp.log_sha256,
                       result_file=stamp.result_file, seconds=stamp.seconds)
        report = Report.from_json(document)
        not_judged = tuple(report.not_judged)
        worst, signal = _worst_g(report.segments, not_judged)
        shares = {} if report.actuators is None else dict(report.actuators.shares)
        effort_ratio, effort_actuator = _worst_effort(shares)
        effort = report.actuators
        coverage = report.coverage
        return cls(
            log=log, verdict=report.verdict, format=report.format, vehicle=report.vehicle,
            fleet_vehicle=fleet_vehicle, start_time_utc=report.start_time_utc,
            duration_s=report.duration_s, not_operating_s=report.not_operating_s,
            completeness=None if report.completeness is None else report.completeness.status,
            not_judged=not_judged, coverage=None if coverage is None else coverage.engine(),
            component=report.component, candidates=report.candidates, case=report.case,
            onset_s=report.onset_s, detected_at_s=report.detected_at_s,
            worst_g_ratio=worst, worst_g_signal=signal, segments=len(report.segments),
            routine_segments=sum(1 for s in report.segments if s.mode == "routine"),
            substituted_signal=None if report.substitution is None
            else report.substitution.signal,
            weakened_thrust_fraction=None if report.degradation is None
            else report.degradation.thrust_fraction,
            driven_harder=tuple(n for n, e in shares.items() if e.driven_harder),
            worst_effort_ratio=effort_ratio, worst_effort_actuator=effort_actuator,
            effort_onset_s=None if effort is None else effort.onset_s,
            effort_detected_at_s=None if effort is None else effort.alarm_s,
            recommended_dms=() if report.active_diagnosis is None
            else report.active_diagnosis.recommended_dms,
            autopilot_alarms=() if report.autopilot is None
            else tuple(a.text for a in report.autopilot.alarms),
            model=report.model.name, model_path=report.model.path,
            log_sha256=stamp.log_sha256, result_file=stamp.result_file, seconds=stamp.seconds,
            bits={str(k): int(v) for k, v in report.b.items()},
            margins=_margins(report, set(not_judged), shares))


@dataclass(frozen=True)
class AuditStamp:
    """What the audit stored beside a report: which log (its digest), where, how long it
    took, and which vehicle of the fleet."""

    log_sha256: str | None = None
    result_file: str | None = None
    seconds: float | None = None
    vehicle: str | None = None

    @classmethod
    def from_json(cls, stamp: object) -> "AuditStamp":
        if not isinstance(stamp, Mapping):
            return cls()
        vehicle = stamp.get("vehicle")
        identity = vehicle.get("id") if isinstance(vehicle, Mapping) else None
        seconds = stamp.get("seconds")
        return cls(_text(stamp.get("log_sha256")), _text(stamp.get("result_file")),
                   float(seconds) if isinstance(seconds, int | float) else None,
                   None if identity is None else str(identity))


def _text(value: object) -> str | None:
    return None if value is None else str(value)


def _segment_ratios(segments: Sequence[SegmentPart], not_judged: Collection[str]
                    ) -> Iterator[tuple[str, float]]:
    """(signal, largest g / threshold) of each judged signal in each segment."""
    for segment in segments:
        for signal, g in segment.max_g.items():
            threshold = segment.thresholds.get(signal)
            if signal not in not_judged and g is not None and threshold:
                yield signal, g / threshold


def _worst_g(segments: Sequence[SegmentPart], not_judged: Collection[str]
             ) -> tuple[float | None, str | None]:
    """The largest g relative to its threshold over all segments and judged signals."""
    ratio, signal = max(((r, s) for s, r in _segment_ratios(segments, not_judged)),
                        default=(None, None))
    return (None if ratio is None else round(ratio, 4)), signal


def _worst_effort(shares: Mapping[str, SharePart]) -> tuple[float | None, str | None]:
    """The judged actuator whose share of the effort came closest to its threshold."""
    judged = [(entry.over_threshold, name) for name, entry in shares.items()
              if entry.over_threshold is not None]
    return max(judged, default=(None, None))


def _margins(report: Report, not_judged: set[str], shares: Mapping[str, SharePart]
             ) -> dict[str, float]:
    """The peak ratio to the threshold per judged sensor (g, the largest over the
    segments) and per judged actuator (its commands against the motion, "NAME"; its share
    of the effort, "NAME share")."""
    ratios: dict[str, float] = {}
    for signal, ratio in _segment_ratios(report.segments, not_judged):
        ratios[signal] = max(ratios.get(signal, 0.0), ratio)
    check = report.commands_check
    for actuator, peak in ({} if check is None else check.peak_over_threshold).items():
        if peak is not None and math.isfinite(peak) and check is not None and \
                actuator not in check.not_judged:
            ratios[actuator] = float(peak)
    for actuator, entry in shares.items():
        if entry.over_threshold is not None and math.isfinite(entry.over_threshold):
            ratios[f"{actuator} share"] = float(entry.over_threshold)
    return ratios
