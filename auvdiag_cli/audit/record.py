"""One log's result in an audit, parsed once from the report the audit stored for it (or
its error) into typed values: what the table, the trend and the fleet PDF read."""

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from auvdiag_cli.engine.coverage import Coverage

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
    recommended_dms: tuple[str, ...] = ()
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
        """A NORMAL over less than every signal and actuator of the profile."""
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
    def from_report(cls, report: Document) -> "AuditRecord":
        """Parse a stored per-log record (a JSON report with the audit's stamp, or an
        error); a key a report from an older release lacks takes its empty value."""
        segments = report.get("segments") or []
        not_judged = tuple(report.get("not_judged") or {})
        worst, signal = _worst_g(segments, not_judged)
        shares = (report.get("actuators") or {}).get("shares") or {}
        effort_ratio, effort_actuator = _worst_effort(shares)
        audit = report.get("audit") or {}
        model = report.get("model") or {}
        return cls(
            log=str(report["log"]), error=report.get("error"), verdict=report.get("verdict"),
            format=report.get("format"), vehicle=report.get("vehicle"),
            fleet_vehicle=str((audit.get("vehicle") or {}).get("id")
                              or Path(report["log"]).parent.name or "."),
            start_time_utc=report.get("start_time_utc"), duration_s=report.get("duration_s"),
            not_operating_s=report.get("not_operating_s"),
            completeness=(report.get("completeness") or {}).get("status"),
            not_judged=not_judged, coverage=Coverage.from_dict(report["coverage"])
            if report.get("coverage") else None,
            component=report.get("component"),
            candidates=tuple(report.get("candidates") or ()), case=report.get("case"),
            onset_s=report.get("onset_s"), detected_at_s=report.get("detected_at_s"),
            worst_g_ratio=worst, worst_g_signal=signal, segments=len(segments),
            routine_segments=sum(1 for s in segments if s.get("mode") == "routine"),
            substituted_signal=(report.get("substitution") or {}).get("signal"),
            weakened_thrust_fraction=(report.get("degradation") or {}).get("thrust_fraction"),
            driven_harder=tuple(n for n, e in shares.items() if e.get("driven_harder")),
            worst_effort_ratio=effort_ratio, worst_effort_actuator=effort_actuator,
            recommended_dms=tuple((report.get("active_diagnosis") or {}).get(
                "recommended_dms") or ()),
            model=model.get("name"), model_path=model.get("path"),
            log_sha256=audit.get("log_sha256"), result_file=audit.get("result_file"),
            seconds=audit.get("seconds"),
            bits={str(k): int(v) for k, v in (report.get("b") or {}).items()},
            margins=_margins(report, segments, set(not_judged), shares))


def _worst_g(segments: Sequence[Document], not_judged: Sequence[str]
             ) -> tuple[float | None, str | None]:
    """The largest g relative to its threshold over all segments and judged signals."""
    worst: tuple[float | None, str | None] = (None, None)
    for segment in segments:
        for signal, g in (segment.get("max_g") or {}).items():
            if signal in not_judged:
                continue
            threshold = (segment.get("thresholds") or {}).get(signal)
            if g is not None and threshold and (worst[0] is None or g / threshold > worst[0]):
                worst = (round(g / threshold, 4), signal)
    return worst


def _worst_effort(shares: Document) -> tuple[float | None, str | None]:
    """The judged actuator whose share of the effort came closest to its threshold."""
    judged = [(entry["over_threshold"], name) for name, entry in shares.items()
              if entry.get("over_threshold") is not None]
    return max(judged, default=(None, None))


def _margins(report: Document, segments: Sequence[Document], not_judged: set[str],
             shares: Document) -> dict[str, float]:
    """The peak ratio to the threshold per judged sensor (g, the largest over the
    segments) and per judged actuator (its commands against the motion, "NAME"; its share
    of the effort, "NAME share")."""
    ratios: dict[str, float] = {}
    for segment in segments:
        for signal, g in (segment.get("max_g") or {}).items():
            threshold = (segment.get("thresholds") or {}).get(signal)
            if signal in not_judged or g is None or not threshold:
                continue
            ratios[signal] = max(ratios.get(signal, 0.0), g / threshold)
    check = report.get("commands_check") or {}
    for actuator, ratio in (check.get("peak_over_threshold") or {}).items():
        if ratio is not None and math.isfinite(ratio) and actuator not in \
                (check.get("not_judged") or {}):
            ratios[actuator] = float(ratio)
    for actuator, entry in shares.items():
        ratio = entry.get("over_threshold")
        if ratio is not None and math.isfinite(ratio):
            ratios[f"{actuator} share"] = float(ratio)
    return ratios
