"""model.json's `calibration` entry: how `calibrate` set the thresholds, for people."""

from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from auvdiag_cli.jobs.calibrate import CalibrationResult


def calibration_record(result: "CalibrationResult", normal_logs: Sequence[Path],
                       floor_at_profile: bool) -> dict[str, Any]:
    budget = result.budget
    return {
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "method": "threshold = margin x the largest g on the normal logs, per mode and "
                  "signal; the g of logs the model was trained on multiplied by the widening"
                  if budget is None else
                  "thresholds to a false-alarm budget: each judge's statistic on the normal "
                  "logs fitted (g and extra effort: Gumbel law of per-log peaks; starts: "
                  "Student-t), the budget shared among the judges; margin rule where a judge "
                  "has too few logs",
        "false_alarm_budget": None if budget is None else budget.to_json(),
        "margin": result.margin,
        "floor_at_profile": floor_at_profile,
        "normal_logs": [p.name for p in normal_logs],
        "in_sample_logs": result.in_sample_logs,
        "change_test_also_on_logs_trained_on": list(result.change_trained_on),
        "widening": result.widening,
        "normal_hours": round(result.normal_hours, 4),
        "false_alarms_on_normal_logs": 0 if budget is None else budget.in_sample_alarmed,
        # The rule-of-three bound holds only where no calibration log alarms (the margin rule).
        "false_alarm_rate_upper_95_per_hour": round(result.false_alarm_bound_per_hour, 3)
        if budget is None else None,
        "modes": [{"mode": m.mode, "samples": m.samples, "max_g": m.max_g,
                   "thresholds": m.thresholds, "kept_profile_default": m.kept_default,
                   "not_judged_kept_profile_threshold": list(m.skipped),
                   "set_by": {k: {"log": e.set_by, "peak_g": e.peak, "next_log_peak_g":
                                  e.next_peak} for k, e in m.evidence.items()}}
                  for m in result.modes],
        "warnings": result.warnings,
        "relation_thresholds_raised": result.relation_thresholds_raised,
        "start_thresholds_raised": result.start_thresholds_raised,
        "faulty_logs": [c.__dict__ for c in result.faulty],
    }

