"""What `calibrate` found (`CalibrationResult`), and model.json's `calibration` entry that
records it for people."""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from auvdiag_cli.jobs.budget import BudgetThresholds
from auvdiag_cli.jobs.change_calibration import ChangeThresholds
from models.card import Refused
from models.effort_model import EffortModel


@dataclass(frozen=True)
class SignalEvidence:
    """Which log set a signal's threshold in one mode, and the next log's peak beside it
    (the threshold if that log were left out would be margin x next_peak)."""

    set_by: str
    peak: float
    next_peak: float | None

    @property
    def dominance(self) -> float | None:
        if self.next_peak is None or self.next_peak <= 0:
            return None
        return self.peak / self.next_peak


@dataclass(frozen=True)
class ModeCalibration:
    mode: str
    samples: int
    hours: float
    max_g: dict[str, float]
    thresholds: dict[str, float]
    kept_default: bool
    evidence: dict[str, SignalEvidence]     # the judged signals only
    # Not judged by the replay, each with why: the profile's thresholds kept.
    skipped: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class FaultyCheck:
    log: str
    verdict: str
    component: str | None
    candidates: tuple[str, ...]
    peak_ratio: float     # the largest g / threshold of a judged signal anywhere in the log


@dataclass(frozen=True)
class CalibrationResult:
    margin: float
    modes: list[ModeCalibration]
    thresholds: dict[str, dict[str, float]]
    normal_hours: float
    false_alarm_bound_per_hour: float
    faulty: list[FaultyCheck]
    in_sample_logs: list[str]           # calibration logs the model was trained on
    widening: dict[str, float]          # per signal, applied to the in-sample logs' g
    warnings: list[str]
    relation_thresholds_raised: dict[str, float]   # command -> extra effort now allowed
    start_thresholds_raised: list[str]             # sensors whose start allowance was raised
    effort: EffortModel | Refused | None = None    # the refitted effort model, if any
    effort_notes: tuple[str, ...] = ()             # calibration logs it left out, and why
    budget: BudgetThresholds | None = None         # --false-alarm-rate: the fitted judges
    # The change test: statistic -> signal -> (largest on these logs, its threshold);
    # empty where no log is long enough to judge it.
    change: ChangeThresholds = field(default_factory=dict)
    change_trained_on: tuple[str, ...] = ()   # logs trained on whose peaks it counted too
    days: tuple[str, ...] = ()     # the UTC days of the normal logs (none: not UTC clocks)
    # input -> statistic -> signal: the change test's thresholds for a log without that
    # input, where higher (`jobs.change_unfed`).
    change_unfed: dict[str, dict[str, dict[str, float]]] = field(default_factory=dict)
    # sensor -> (the signatures it is judged within, why never alone): no threshold of its own.
    change_within: dict[str, tuple[tuple[str, ...], str]] = field(default_factory=dict)
    # signal -> how long the normal logs let the change test judge it, all together, where
    # too little to set its thresholds (it gets none).
    change_too_little: Mapping[str, float] = field(default_factory=dict)



def calibration_record(result: CalibrationResult, normal_logs: Sequence[Path],
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
        "days": list(result.days),
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

