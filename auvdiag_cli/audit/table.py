"""The audit table: one row per log, the record's fields flattened (SPEC §5), written as CSV
and Parquet, each atomically."""

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.engine.coverage import Coverage

if TYPE_CHECKING:
    import pandas as pd

FIXED_COLUMNS = ["log", "format", "vehicle", "fleet_vehicle", "start_time_utc", "duration_s",
                 "not_operating_s", "verdict", "completeness", "not_judged", "signals_judged",
                 "actuators_judged", "coverage_complete", "component", "candidates", "case",
                 "onset_s", "detected_at_s",
                 "worst_g_ratio", "worst_g_signal", "segments", "routine_segments",
                 "substituted_signal", "weakened_thrust_fraction", "driven_harder",
                 "worst_effort_ratio", "worst_effort_actuator", "effort_onset_s",
                 "effort_detected_at_s", "recommended_dms", "autopilot_alarms",
                 "model", "error", "log_sha256", "result_file", "seconds"]


def table_row(record: AuditRecord) -> dict[str, object]:
    """One table row: the record's fields, lists joined with ";", b per signal."""
    row: dict[str, object] = {
        "log": record.log, "format": record.format, "vehicle": record.vehicle,
        "fleet_vehicle": record.fleet_vehicle, "start_time_utc": record.start_time_utc,
        "duration_s": record.duration_s, "not_operating_s": record.not_operating_s,
        "verdict": record.verdict or ("error" if record.error else None),
        "completeness": record.completeness, "not_judged": ";".join(
            record.not_judged if record.coverage is None
            else record.coverage.signals_not_judged),
        **_coverage_columns(record.coverage),
        "component": record.component, "candidates": ";".join(record.candidates),
        "case": record.case, "onset_s": record.onset_s, "detected_at_s": record.detected_at_s,
        "worst_g_ratio": record.worst_g_ratio, "worst_g_signal": record.worst_g_signal,
        "segments": record.segments, "routine_segments": record.routine_segments,
        "substituted_signal": record.substituted_signal,
        "weakened_thrust_fraction": record.weakened_thrust_fraction,
        "driven_harder": ";".join(record.driven_harder),
        "worst_effort_ratio": record.worst_effort_ratio,
        "worst_effort_actuator": record.worst_effort_actuator,
        "effort_onset_s": record.effort_onset_s,
        "effort_detected_at_s": record.effort_detected_at_s,
        "recommended_dms": ";".join(record.recommended_dms),
        "autopilot_alarms": ";".join(record.autopilot_alarms), "model": record.model,
        "error": record.error, "log_sha256": record.log_sha256,
        "result_file": record.result_file, "seconds": record.seconds}
    row |= {f"b_{name}": bit for name, bit in record.bits.items()}
    return row


def _coverage_columns(coverage: Coverage | None) -> dict[str, object]:
    """"judged/total" for the signals and the actuators, and whether that is everything."""
    if coverage is None:
        return {"signals_judged": None, "actuators_judged": None, "coverage_complete": None}

    return {"signals_judged": f"{len(coverage.signals_judged)}/{len(coverage.signals)}",
            "actuators_judged": f"{len(coverage.actuators_judged)}/{len(coverage.actuators)}",
            "coverage_complete": coverage.complete}


def build_table(records: Sequence[AuditRecord]) -> "pd.DataFrame":
    import pandas as pd

    rows = [table_row(r) for r in records]
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
