"""`auvdiag calibrate`: thresholds from the g the model reaches on normal logs.

For each diagnosis mode (mission, and each DMS) and signal, the threshold is the largest g
seen on the normal logs times a margin (a mode with too little data keeps the profile's
threshold unless that margin over its largest g is higher). On those logs that gives zero
false alarms by construction; the false-alarm rate it implies elsewhere is stated as the
rule-of-three upper bound (no event in T hours: fewer than 3/T per hour at 95 % confidence).
Faulty logs, when given, are diagnosed with the new thresholds to show the detection margin.
The effort shares (`models.effort`) are refitted with the normal logs added.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from auvdiag_cli.digest import log_digest
from auvdiag_cli.engine.autopilot_words import trouble_in_normal_log
from auvdiag_cli.engine.change_columns import change_judged
from auvdiag_cli.engine.change_signatures import judged_within
from auvdiag_cli.engine.change_statistics import STRIDE_STEPS
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.diagnosis import diagnose_ingested
from auvdiag_cli.engine.ingest import IngestedLog, ingest
from auvdiag_cli.engine.judging import replay_judged, replay_left_out, skilled
from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.engine.start_check import StartReading, raise_thresholds, start_reading
from auvdiag_cli.jobs.budget import (
    BudgetThresholds,
    FalseAlarmBudget,
    budget_thresholds,
    change_judges,
    command_judges,
    g_judges,
    start_judges,
    with_command_thresholds,
)
from auvdiag_cli.jobs.calibration_result import (
    CalibrationResult,
    FaultyCheck,
    ModeCalibration,
    SignalEvidence,
    calibration_record,
)
from auvdiag_cli.jobs.change_calibration import (
    DOMINANCE_WARNING,
    ChangeEvidence,
    change_entry,
    change_evidence,
    change_thresholds,
    dominated_by_one_log,
)
from auvdiag_cli.jobs.change_unfed import unfed_thresholds
from auvdiag_cli.jobs.effort import learn_effort_model, refit_effort
from auvdiag_cli.jobs.healthy import NO_HEALTHY_PARTS, HealthyParts, announce_healthy_parts
from auvdiag_cli.jobs.operating import read_operating
from auvdiag_cli.jobs.relate import relation_log, widen_thresholds
from auvdiag_cli.jobs.thin_evidence import thin_evidence, utc_days
from auvdiag_cli.numeric import peak
from auvdiag_cli.vehicle.profile import MISSION_MODE, Profile
from auvdiag_errors import UsageError
from models.card import Refused
from models.effort import DEFAULT_FALSE_ALARM_RATE
from models.effort_model import EffortModel
from models.store import LoadedModel

MIN_SAMPLES_PER_MODE = 300     # 30 s at 10 Hz: fewer and the profile's threshold is kept
# One log's peak g this many times the next log's: that log alone sets the threshold.
# Logs the model was trained on give a g that is too low (the model has seen them): their g
# counts only widened by the ratio of the model's held-out error to its error on these logs,
# per signal, and at least by this factor.
IN_SAMPLE_MIN_WIDENING = 1.25


def _mode_key(segment_name: str) -> str:
    return MISSION_MODE if segment_name == "MISSION" else segment_name


def g_by_mode(diagnosis: Diagnosis) -> dict[str, np.ndarray]:
    """The log's g per mode (`Diagnosis.judged_g`: NaN where it set a signal aside)."""
    g, time_s = diagnosis.judged_g, diagnosis.histories.time_s
    result: dict[str, list[np.ndarray]] = {}
    for part in diagnosis.segments:
        inside = (time_s >= part.segment.start_s) & (time_s <= part.segment.end_s)
        result.setdefault(_mode_key(part.segment.name), []).append(g[inside])
    return {mode: np.concatenate(parts) for mode, parts in result.items()}


def _widening(model: LoadedModel, diagnoses: Sequence[Diagnosis],
              sensor_names: tuple[str, ...]) -> dict[str, float]:
    """Held-out error / error on these (in-sample) logs, per signal, at least
    IN_SAMPLE_MIN_WIDENING."""
    residuals = np.concatenate([d.histories.matching.measured - d.histories.matching.modelled
                                for d in diagnoses if d.histories.matching is not None])
    heldout = model.card.heldout_error_rms
    widening = {}
    for i, name in enumerate(sensor_names):
        values = residuals[:, i][np.isfinite(residuals[:, i])]
        in_sample = float(np.sqrt(np.mean(values ** 2))) if values.size else 0.0
        error = heldout.get(name)
        ratio = error / in_sample if in_sample > 0 and error else IN_SAMPLE_MIN_WIDENING
        widening[name] = round(max(IN_SAMPLE_MIN_WIDENING, ratio), 3)
    return widening


def _evidence(per_log: list[tuple[str, np.ndarray]], column: int) -> SignalEvidence:
    peaks = sorted(((peak(g[:, column]), name) for name, g in per_log), reverse=True)
    return SignalEvidence(peaks[0][1], round(peaks[0][0], 3),
                          round(peaks[1][0], 3) if len(peaks) > 1 else None)


def _check_faulty(path: Path, profile: Profile, calibrated: LoadedModel) -> FaultyCheck:
    """A log with a known fault, diagnosed with the new thresholds: is it still caught?"""
    d = diagnose_ingested(ingest(path, profile), profile, calibrated)
    histories = d.histories
    judged = [i for i, name in enumerate(profile.sensor_names) if name not in d.not_judged]
    ratio = (peak(histories.matching.g_percent[:, judged] / histories.thresholds[:, judged])
             if histories.matching and judged else 0.0)
    return FaultyCheck(str(path), d.verdict, d.component, d.candidates, round(ratio, 2))


@dataclass(frozen=True)
class CalibrateOptions:
    """How thresholds are set. ``margin``: threshold = margin x the largest normal g.
    ``budget``: thresholds to a false-alarm rate instead of the margin rule wherever a judge
    has enough logs (`jobs.budget`). ``floor_at_profile``: never below the profile's
    threshold for the mode (a signal a sequence hardly moves has a tiny normal g, and a
    threshold of 1.5 times noise would trip on the next dive's noise)."""

    margin: float = 1.5
    budget: FalseAlarmBudget | None = None
    floor_at_profile: bool = False
    healthy: HealthyParts = NO_HEALTHY_PARTS     # only these parts of the logs listed


DEFAULT_CALIBRATION = CalibrateOptions()


def calibrate(model: LoadedModel, profile: Profile, normal_logs: Sequence[Path],
              faulty_logs: Sequence[Path] = (), options: CalibrateOptions = DEFAULT_CALIBRATION,
              progress: Callable[[str], None] = lambda _: None) -> CalibrationResult:
    """Derive thresholds; the model's entries are updated (not yet written). Logs in which
    the vehicle never operates are left out; ``faulty_logs`` are diagnosed with the new
    thresholds to show the margin."""
    margin, budget, floor_at_profile = options.margin, options.budget, options.floor_at_profile
    if margin < 1.0:
        raise UsageError("--margin below 1 would raise alarms on the calibration logs")
    announce_healthy_parts(options.healthy, normal_logs, progress)
    kept = read_operating(normal_logs, lambda path: ingest(
        path, profile, part=options.healthy.of(path)), progress, "calibrate with")
    normal_logs, ingested = list(kept), list(kept.values())
    digests = [log_digest(p) for p in normal_logs]
    # Judge the calibration logs without any earlier calibration: raw g is what counts.
    base = model.with_entries(thresholds=profile.thresholds)
    diagnoses = _diagnosed(normal_logs, ingested, profile, base, progress)
    in_sample, widening, per_log, labels = _g_per_log(model, profile, normal_logs, digests,
                                                      diagnoses)
    judged = replay_judged(model, profile)
    modes = margin_modes(labels, per_log, profile, margin, floor_at_profile, model)
    hours = sum(m.hours for m in modes)
    if hours == 0:
        raise UsageError("no usable normal data in the calibration logs")
    readings = _start_readings(diagnoses, profile.dt_s)
    checks = [d.command_check for d in diagnoses]
    raised = widen_thresholds(model, checks, margin)
    start, starts_raised = raise_thresholds(model.card.start_state, readings, margin)
    if start.usable:
        model.update_entries(start_state=start)
    training = model.card.change_training
    evidence = change_evidence(diagnoses, skilled(model, profile), model, profile,
                               training.without(set(digests), STRIDE_STEPS),
                               len(training.logs) if training.stale(STRIDE_STEPS) else 0)
    fitted = None if budget is None else _apply_budget(
        model, profile, budget, per_log, modes, readings, checks, judged,
        [float(log.frame.operating.sum()) * profile.dt_s / 3600 for log in ingested], evidence)
    change = change_thresholds(evidence, margin, fitted)
    unfed = unfed_thresholds(ingested, model, profile, margin, fitted, evidence.scales, change,
                             progress)
    model.update_entries(change_test=change_entry(change, evidence, unfed))
    if fitted is not None:
        modes = _with_budget(modes, fitted, profile, floor_at_profile)
    thresholds = {**{m: dict(v) for m, v in profile.thresholds.items()},
                  **{m.mode: m.thresholds for m in modes}}
    model.update_entries(thresholds=thresholds)
    effort, effort_notes = _refit_effort(model, profile, ingested,
                                         None if fitted is None else fitted.effort_rate)
    result = CalibrationResult(
        margin, modes, thresholds, hours, 3.0 / hours,
        [_check_faulty(path, profile, model) for path in faulty_logs],
        [p.name for p in in_sample], widening,
        _warnings(modes, in_sample, ingested, widening, evidence, budget is not None),
        raised, [profile.sensor_names[i] for i in starts_raised], effort, tuple(effort_notes),
        fitted, change, evidence.trained_on, utc_days(ingested), unfed,
        judged_within(profile.actuators, profile.sensors,
                      change_judged(model, skilled(model, profile))), evidence.too_little)
    model.update_entries(calibration=calibration_record(result, normal_logs,
                                                            floor_at_profile))
    return result


def _start_readings(diagnoses: Sequence[Diagnosis], dt_s: float
                    ) -> list[StartReading | None]:
    """Each log's start as the start check reads it (None: not matched)."""
    return [None if h.matching is None else start_reading(h.commands, h.matching.measured, dt_s)
            for h in (d.histories for d in diagnoses)]


def _g_per_log(model: LoadedModel, profile: Profile, logs: Sequence[Path],
               digests: Sequence[str], diagnoses: Sequence[Diagnosis]
               ) -> tuple[list[Path], dict[str, float], list[dict[str, np.ndarray]], list[str]]:
    """The logs the model was trained on (recognised by their content digests), the
    widening their in-sample g gets, each log's g per mode (widened there) and its label."""
    in_sample = [p for p, d in zip(logs, digests, strict=True)
                 if d in model.card.training_digests]
    widening = _widening(model, [d for p, d in zip(logs, diagnoses, strict=True)
                                 if p in in_sample], profile.sensor_names) if in_sample else {}
    factor = np.asarray([widening.get(name, 1.0) for name in profile.sensor_names])
    per_log = [{mode: g * factor if path in in_sample else g
                for mode, g in g_by_mode(d).items()}
               for path, d in zip(logs, diagnoses, strict=True)]
    labels = [f"{p.name} (in-sample, widened)" if p in in_sample else p.name for p in logs]
    return in_sample, widening, per_log, labels


def margin_modes(labels: Sequence[str], per_log: Sequence[dict[str, np.ndarray]],
                  profile: Profile, margin: float, floor_at_profile: bool,
                  model: LoadedModel) -> list[ModeCalibration]:
    """Each mode's thresholds by calibrate's rule: margin x the largest g on the logs, for
    the signals the replay judges with the ``model`` (those it leaves out raise no alarm:
    their profile thresholds stay)."""
    left_out = replay_left_out(model, profile)
    judged = [name for name in profile.sensor_names if name not in left_out]
    modes = []
    for mode in sorted({mode for g in per_log for mode in g}):
        parts = [(label, g[mode]) for label, g in zip(labels, per_log, strict=True)
                 if mode in g]
        g = np.concatenate([part for _, part in parts])
        count = int(np.isfinite(g).all(axis=1).sum())
        peaks = {name: peak(g[:, i]) for i, name in enumerate(profile.sensor_names)}
        keep = count < MIN_SAMPLES_PER_MODE or mode not in (*profile.dms, MISSION_MODE)
        # Too little data cannot lower the profile's thresholds, but what it shows still
        # raises them: no calibration log may alarm.
        floor = profile.thresholds_for(mode) if floor_at_profile or keep else {}
        default = profile.thresholds_for(mode)
        modes.append(ModeCalibration(
            mode, count, count * profile.dt_s / 3600, {k: round(v, 3) for k, v in peaks.items()},
            {name: round(max(margin * value, floor.get(name, 0.0)), 2) if name in judged
             else default[name] for name, value in peaks.items()}, keep,
            {name: _evidence(parts, i) for i, name in enumerate(profile.sensor_names)
             if name in judged}, {n: left_out[n] for n in profile.sensor_names if n in left_out}))
    return modes


def _apply_budget(model: LoadedModel, profile: Profile, budget: FalseAlarmBudget,
                  per_log: Sequence[dict[str, np.ndarray]], modes: Sequence[ModeCalibration],
                  readings: Sequence[StartReading | None],
                  checks: Sequence[CommandCheck | None], judged: Sequence[str],
                  log_hours: Sequence[float], change: ChangeEvidence) -> BudgetThresholds:
    """Fit the judges to the budget and set the start and command thresholds they give in
    model's entries (g's go into the modes, `_with_budget`)."""
    start, relations = model.card.start_state, model.relations
    judges = [*g_judges(per_log, [m.mode for m in modes if not m.kept_default], judged,
                        profile.sensor_names),
              *start_judges(start, readings, profile.sensor_names),
              *command_judges(relations, checks, profile.command_names),
              *change_judges(change.peaks, change.judged, len(change.trained_on))]
    actuators = sum(len(group.members) for group in profile.effort_groups)
    fitted = budget_thresholds(judges, actuators, budget, log_hours)
    if start.usable:
        allowed = list(start.thresholds)
        for (_, name), value in fitted.thresholds("start").items():
            allowed[profile.sensor_names.index(name)] = value
        model.update_entries(start_state=replace(start, thresholds=tuple(allowed)))
    if relations is not None:
        model.update_entries(command_relations=with_command_thresholds(
            relations, fitted.thresholds("command"), profile.command_names))
    return fitted


def _diagnosed(paths: Sequence[Path], logs: Sequence[IngestedLog], profile: Profile,
               model: LoadedModel, progress: Callable[[str], None]) -> list[Diagnosis]:
    """Each normal log diagnosed, with a warning for each in which the autopilot reported
    trouble while it operated."""
    diagnoses = [diagnose_ingested(log, profile, model) for log in logs]
    for path, diagnosis in zip(paths, diagnoses, strict=True):
        trouble = trouble_in_normal_log(path.name, diagnosis.autopilot)
        if trouble:
            progress(trouble)
    return diagnoses


def _with_budget(modes: Sequence[ModeCalibration], fitted: BudgetThresholds,
                 profile: Profile, floor_at_profile: bool) -> list[ModeCalibration]:
    g = fitted.thresholds("g")
    result = []
    for m in modes:
        floor = profile.thresholds_for(m.mode) if floor_at_profile else {}
        result.append(replace(m, thresholds={
            name: round(max(g[(m.mode, name)], floor.get(name, 0.0)), 2)
            if (m.mode, name) in g else value for name, value in m.thresholds.items()}))
    return result


def _refit_effort(model: LoadedModel, profile: Profile, logs: Sequence[IngestedLog],
                  false_alarm_rate: float | None
                  ) -> tuple[EffortModel | Refused | None, list[str]]:
    """The effort model with these normal logs added (learnt from them where the model has
    none yet), written into the model's entries; None where the profile has no groups.
    ``false_alarm_rate``: a new budget (a share of normal logs) for its thresholds."""
    if not profile.effort_groups:
        return None, []
    relations = [relation_log(log, profile) for log in logs]
    if model.effort is None:
        effort, notes = learn_effort_model(
            relations, profile, DEFAULT_FALSE_ALARM_RATE if false_alarm_rate is None
            else false_alarm_rate)
    else:
        effort, notes = refit_effort(model.effort, relations, profile, false_alarm_rate)
    if isinstance(effort, EffortModel):
        model.update_entries(effort=effort)
    return effort, notes


def _warnings(modes: Sequence[ModeCalibration], in_sample: Sequence[Path],
              normal_logs: Sequence[IngestedLog], widening: dict[str, float],
              change: ChangeEvidence, budgeted: bool) -> list[str]:
    warnings = (dominated_by_one_log(change, [log.signals.path.name for log in normal_logs])
                + thin_evidence(normal_logs, budgeted, len(change.peaks),
                                len(normal_logs) - len(in_sample)))
    if in_sample:
        which = ("every calibration log was" if len(in_sample) == len(normal_logs)
                 else f"{len(in_sample)} of the calibration logs were")
        warnings.append(
            f"{which} used to train the model: their g is in-sample (too low) and counts "
            "only widened by the held-out / in-sample error ratio ("
            + ", ".join(f"{k} x{v:g}" for k, v in widening.items())
            + "); calibrate on normal logs the model has not seen")
    if change.trained_not_counted:
        warnings.append(
            f"the change test's statistics the model keeps for the {change.trained_not_counted}"
            " log(s) it was trained on were measured by an earlier form of the test (before "
            "it judged a window every step, or each way apart): not counted here; train the "
            "model again to count them")
    for mode in modes:
        if mode.kept_default:
            continue
        for name, evidence in mode.evidence.items():
            if evidence.dominance is not None and evidence.dominance >= DOMINANCE_WARNING:
                warnings.append(
                    f"{mode.mode} {name}: {evidence.set_by} alone sets the threshold (its peak "
                    f"g {evidence.peak:g} % is {evidence.dominance:.1f}x the next log's "
                    f"{evidence.next_peak:g} %): check that log for a spike, a fault or a "
                    "disturbance")
    return warnings
