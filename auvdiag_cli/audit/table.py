"""The audit table: one row per log, the JSON report's fields flattened (SPEC §5), written as
CSV and Parquet, each atomically."""

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd

FIXED_COLUMNS = ["log", "format", "vehicle", "fleet_vehicle", "start_time_utc", "duration_s",
                 "not_operating_s", "verdict", "completeness", "not_judged", "signals_judged",
                 "actuators_judged", "coverage_complete", "component", "candidates", "case",
                 "onset_s", "detected_at_s",
                 "worst_g_ratio", "worst_g_signal", "segments", "routine_segments",
                 "substituted_signal", "weakened_thrust_fraction", "driven_harder",
                 "worst_effort_ratio", "worst_effort_actuator", "recommended_dms",
                 "model", "error", "log_sha256", "result_file", "seconds"]


def _worst_g(segments: list[dict[str, Any]], not_judged: Sequence[str]
             ) -> tuple[float | None, str | None]:
    """The largest g relative to its threshold over all segments and judged signals."""
    worst: tuple[float | None, str | None] = (None, None)
    for segment in segments:
        for signal, g in segment["max_g"].items():
            if signal in not_judged:
                continue
            threshold = segment["thresholds"].get(signal)
            if g is not None and threshold and (worst[0] is None or g / threshold > worst[0]):
                worst = (round(g / threshold, 4), signal)
    return worst


def _worst_effort(record: dict[str, Any]) -> tuple[float | None, str | None]:
    """The judged actuator whose share of the effort came closest to its threshold."""
    shares = (record.get("actuators") or {}).get("shares") or {}
    judged = [(entry["over_threshold"], name) for name, entry in shares.items()
              if entry.get("over_threshold") is not None]
    return max(judged, default=(None, None))


def _coverage_columns(coverage: dict[str, Any] | None) -> dict[str, Any]:
    """"judged/total" for the signals and the actuators, and whether that is everything."""
    if not coverage:
        return {"signals_judged": None, "actuators_judged": None, "coverage_complete": None}

    def share(part: dict[str, list[str]]) -> str:
        return f"{len(part['judged'])}/{len(part['judged']) + len(part['not_judged'])}"

    return {"signals_judged": share(coverage["signals"]),
            "actuators_judged": share(coverage["actuators"]),
            "coverage_complete": bool(coverage["complete"])}


def fleet_vehicle_of(record: dict[str, Any]) -> str:
    """The fleet vehicle the audit assigned (audits before it knew: the folder)."""
    assigned = (record.get("audit") or {}).get("vehicle") or {}
    return str(assigned.get("id") or Path(record["log"]).parent.name or ".")


def flatten(record: dict[str, Any]) -> dict[str, Any]:
    """One table row from a stored per-log record (a report, or an error)."""
    segments = record.get("segments") or []
    worst, signal = _worst_g(segments, list(record.get("not_judged") or {}))
    substitution = record.get("substitution") or {}
    degradation = record.get("degradation") or {}
    active = record.get("active_diagnosis") or {}
    audit = record.get("audit", {})
    effort_ratio, effort_actuator = _worst_effort(record)
    row: dict[str, Any] = {
        "log": record["log"], "format": record.get("format"), "vehicle": record.get("vehicle"),
        "fleet_vehicle": fleet_vehicle_of(record),
        "start_time_utc": record.get("start_time_utc"), "duration_s": record.get("duration_s"),
        "not_operating_s": record.get("not_operating_s"),
        "verdict": record.get("verdict", "error" if record.get("error") else None),
        "completeness": (record.get("completeness") or {}).get("status"),
        "not_judged": ";".join(record.get("not_judged") or {}),
        **_coverage_columns(record.get("coverage")),
        "component": record.get("component"),
        "candidates": ";".join(record.get("candidates") or []),
        "case": record.get("case"), "onset_s": record.get("onset_s"),
        "detected_at_s": record.get("detected_at_s"),
        "worst_g_ratio": worst, "worst_g_signal": signal,
        "segments": len(segments),
        "routine_segments": sum(1 for s in segments if s["mode"] == "routine"),
        "substituted_signal": substitution.get("signal"),
        "weakened_thrust_fraction": degradation.get("thrust_fraction"),
        "driven_harder": ";".join(name for name, entry in (
            (record.get("actuators") or {}).get("shares") or {}).items()
            if entry.get("driven_harder")),
        "worst_effort_ratio": effort_ratio, "worst_effort_actuator": effort_actuator,
        "recommended_dms": ";".join(active.get("recommended_dms") or []),
        "model": (record.get("model") or {}).get("name"),
        "error": record.get("error"), "log_sha256": audit.get("log_sha256"),
        "result_file": audit.get("result_file"), "seconds": audit.get("seconds"),
    }
    for name, bit in (record.get("b") or {}).items():
        row[f"b_{name}"] = bit
    return row


def build_table(records: Sequence[dict[str, Any]]) -> "pd.DataFrame":
    import pandas as pd

    rows = [flatten(r) for r in records]
    frame = pd.DataFrame(rows)
    extra = sorted(c for c in frame.columns if c not in FIXED_COLUMNS)
    frame = frame.reindex(columns=FIXED_COLUMNS + extra)
    for column in ("case", *extra):
        frame[column] = frame[column].astype("Int64")
    frame["coverage_complete"] = frame["coverage_complete"].astype("boolean")
    return frame.sort_values("log", kind="stable").reset_index(drop=True)


def write_tables(frame: "pd.DataFrame", output: Path) -> None:
    for name, write in (("audit.csv", lambda p: frame.to_csv(p, index=False)),
                        ("audit.parquet", lambda p: frame.to_parquet(p, index=False))):
        target = output / name
        temporary = target.with_name(f".{name}.tmp")
        write(temporary)
        temporary.replace(target)
