"""The typed report (`reports.report.Report`) built once from a diagnosis: times rounded
as the report gives them, UTC where the log's clock is Unix time, non-finite numbers as
null, and every check's summary sentence."""

import math
from datetime import UTC, datetime

from auvdiag_cli import __version__
from auvdiag_cli.engine.autopilot_words import SaidAlarm
from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.closed_loop import ClosedLoopReplay
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.hypotheses import Hypothesis
from auvdiag_cli.engine.results import (
    EPOCH_CLOCK_NS,
    PAPER_ASSUMPTIONS,
    Diagnosis,
    SegmentResult,
    Verdict,
)
from auvdiag_cli.engine.substitution import Substitution
from auvdiag_cli.reports.report import (
    ActivePart,
    ActuatorsPart,
    AlarmPart,
    AutopilotPart,
    BudgetPart,
    ChangePart,
    ClosedLoopPart,
    CommandsPart,
    CompletenessPart,
    CoveragePart,
    DegradationPart,
    EvidencePart,
    HypothesesPart,
    HypothesisPart,
    JudgedPart,
    MethodPart,
    ModelPart,
    Report,
    SegmentPart,
    SharePart,
    SignaturePart,
    StartPart,
    SubstitutionPart,
)

G_FORMULA = "g_i(k) = 100/(K R_i) * sum_{j=k-K+1..k} |SS_i(j) - SM_i(j)| (mean of K samples)"


def _finite(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else value


def _rounded(value: float | None, digits: int = 5) -> float | None:
    return None if value is None else round(value, digits)


def utc_text(time_ns: int, timespec: str = "seconds") -> str | None:
    """A time as UTC, when its clock is Unix time (not time since boot) and a date at all."""
    if time_ns <= EPOCH_CLOCK_NS:
        return None
    try:
        return datetime.fromtimestamp(time_ns / 1e9, UTC).isoformat(timespec=timespec)
    except (OverflowError, ValueError, OSError):  # a damaged clock is no date
        return None


def _utc_after(start_ns: int, seconds: float | None) -> str | None:
    """A report time as UTC to the millisecond, where the log's clock is Unix time."""
    return None if seconds is None else utc_text(start_ns + round(seconds * 1e9),
                                                 "milliseconds")


def build_report(diagnosis: Diagnosis) -> Report:
    d = diagnosis
    duration = d.histories.duration_s
    completeness = None if d.completeness is None else CompletenessPart(**d.completeness.to_dict())
    coverage = d.coverage
    return Report(
        tool=f"auvdiag {__version__}", log=str(d.log), format=d.format, vehicle=d.vehicle,
        verdict=d.verdict.value, undetermined_because=d.undetermined_because,
        component=d.component, candidates=tuple(d.candidates),
        case=d.case, b=dict(d.b), units=dict(d.sensor_units), detected_at_s=d.detected_at_s,
        onset_s=d.onset_s, onset_error_s=d.onset_error_s,
        duration_s=None if duration is None else round(duration, 3),
        start_time_utc=utc_text(d.start_ns + d.utc_offset_ns, "milliseconds"),
        onset_utc=_utc_after(d.start_ns + d.utc_offset_ns, d.onset_s),
        detected_at_utc=_utc_after(d.start_ns + d.utc_offset_ns, d.detected_at_s),
        completeness=completeness, not_operating_s=d.not_operating_s,
        not_judged=dict(d.not_judged),
        coverage=CoveragePart(
            summary=coverage.counts(), complete=coverage.complete,
            signals=JudgedPart(judged=tuple(coverage.signals_judged),
                               not_judged=tuple(coverage.signals_not_judged)),
            actuators=JudgedPart(judged=tuple(coverage.actuators_judged),
                                 not_judged=tuple(coverage.actuators_not_judged)),
            start_judged=coverage.start_judged, judged_from_s=coverage.judged_from_s),
        segments=tuple(_segment(r) for r in d.segments), segment_source=d.segment_source,
        degradation=None if d.degradation is None else DegradationPart(
            component=d.degradation.component, thrust_fraction=d.degradation.thrust_fraction,
            peak_g_over_threshold=d.degradation.peak_g_ratio),
        hypotheses=_hypotheses(d), commands_check=_command_check(d.command_check),
        start_check=None if d.start_check is None else StartPart(
            summary=d.start_check.describe(d.sensor_units), judged=d.start_check.judged,
            deviation=dict(d.start_check.deviation), allowed=dict(d.start_check.thresholds),
            off=tuple(d.start_check.off), at_s=d.start_check.at_s),
        change_check=_change_check(d.change_check), actuators=_actuators(d.effort_check),
        active_diagnosis=None if d.active is None else ActivePart(
            candidates_before=tuple(d.active.candidates_before),
            candidates_after=tuple(d.active.candidates),
            evidence=tuple(EvidencePart(log=e.log, segment=e.segment, start_s=e.start_s,
                                        b=dict(e.b), tested=tuple(e.tested), faulty=e.faulty)
                           for e in d.active.evidence),
            recommended_dms=tuple(d.active.recommended_dms), conflict=d.active.conflict),
        substitution=_substitution(d.substitution), autopilot=_autopilot(d), model=_model(d),
        method=MethodPart(g=G_FORMULA, window_samples=d.window_samples,
                          decision_window_s=d.decision_window_s,
                          assumptions=tuple(PAPER_ASSUMPTIONS)),
        notes=tuple(d.notes))


def _autopilot(diagnosis: Diagnosis) -> AutopilotPart | None:
    said = diagnosis.autopilot
    if said is None:
        return None
    fault = diagnosis.verdict == Verdict.FAULT
    return AutopilotPart(
        summary=said.describe(fault, diagnosis.onset_s, diagnosis.component),
        other_messages=said.other_messages, alarms=_alarm_parts(said.alarms),
        standing=_alarm_parts(said.standing))


def _alarm_parts(alarms: tuple[SaidAlarm, ...]) -> tuple[AlarmPart, ...]:
    return tuple(AlarmPart(text=a.text, severity=a.severity, first_s=a.first_s,
                           last_s=a.last_s, times=a.times) for a in alarms)


def _model(diagnosis: Diagnosis) -> ModelPart:
    m = diagnosis.model
    return ModelPart(
        name=m.name, vehicle=m.vehicle, path=m.path, weights_sha256=m.weights_sha256,
        created=m.created, heldout_error_rms=None if m.heldout_error_rms is None
        else dict(m.heldout_error_rms), horizon_s=m.horizon_s,
        skill=None if m.skill is None else dict(m.skill), predictors=dict(m.predictors),
        inputs=tuple(m.inputs), thresholds_calibrated=m.thresholds_calibrated,
        false_alarm_rate=None if m.false_alarm_rate is None
        else BudgetPart(rate=m.false_alarm_rate.rate, per=m.false_alarm_rate.per))


def _segment(r: SegmentResult) -> SegmentPart:
    return SegmentPart(name=r.segment.name, start_s=round(r.segment.start_s, 3),
                       end_s=round(r.segment.end_s, 3), mode=r.segment.mode,
                       thresholds=dict(r.segment.thresholds),
                       max_g={k: _finite(v) for k, v in r.max_g.items()}, b=dict(r.b),
                       case=r.case, components=tuple(r.components))


def _substitution(s: Substitution | None) -> SubstitutionPart | None:
    if s is None:
        return None
    tracks = s.tracks
    return SubstitutionPart(
        signal=s.signal, from_s=s.from_s, unit=s.unit, expected_error_rms=s.expected_error_rms,
        truth_error_rms=_rounded(s.truth_error_rms),
        failed_sensor_error_rms=_rounded(s.failed_error_rms),
        track_end_m={name: tuple(round(v, 3) for v in track.end)
                     for name, track in tracks.items()},
        track_end_error_m={name: round(track.distance_to(tracks["truth"]), 3)
                           for name, track in tracks.items()
                           if name != "truth" and "truth" in tracks},
        closed_loop=_closed_loop(s.closed_loop))


def _closed_loop(replay: ClosedLoopReplay | None) -> ClosedLoopPart | None:
    if replay is None:
        return None
    return ClosedLoopPart(from_s=replay.start_s, reached_last_waypoint=replay.reached,
                          finished_s=replay.finished_s, miss_m=replay.miss_m,
                          last_waypoint_m=tuple(replay.last_waypoint),
                          end_m=(round(float(replay.x_m[-1]), 3),
                                 round(float(replay.y_m[-1]), 3)))


def _hypothesis(h: Hypothesis | None) -> HypothesisPart | None:
    return None if h is None else HypothesisPart(
        component=h.component, kind=h.kind, description=h.describe(),
        thrust_fraction=h.thrust_fraction, stuck_at=h.stuck_at,
        peak_g_over_threshold=_finite(h.peak_g_ratio), explains=h.explains,
        ruled_out=h.ruled_out)


def _hypotheses(diagnosis: Diagnosis) -> HypothesesPart | None:
    """The hypothesis test's verdict: the best, the runner-up (another component), the
    margin between them, and whether the pattern table's candidates include the best."""
    test = diagnosis.hypotheses
    if test is None:
        return None
    best = _hypothesis(test.best)
    assert best is not None
    return HypothesesPart(
        best=best, runner_up=_hypothesis(test.runner_up),
        margin=_finite(_rounded(test.margin)),
        table_agrees=(test.best.component in diagnosis.candidates
                      if diagnosis.case is not None else None),
        ranked=tuple(h for h in map(_hypothesis, test.ranked) if h is not None))


def _command_check(check: CommandCheck | None) -> CommandsPart | None:
    if check is None:
        return None
    return CommandsPart(
        summary=check.describe() if check.judged else "no actuator could be judged",
        window_s=check.window_s, extra_effort_allowed=dict(check.thresholds),
        peak_over_threshold=dict(check.peak_ratio), not_judged=dict(check.not_judged),
        alarm_s=check.alarm_s, onset_s=check.onset_s, onset_error_s=check.onset_error_s,
        named=tuple(check.named),
        explained=None if check.explained is None else dict(check.explained),
        extra_effort=check.extra_effort, measure=check.measure)


def _change_check(check: ChangeCheck | None) -> ChangePart | None:
    """The log against its own beginning (null: the model has no change thresholds)."""
    if check is None:
        return None
    return ChangePart(
        summary=check.describe(), judged=check.judged, judged_from_s=check.judged_from_s,
        thresholds={s: dict(v) for s, v in check.thresholds.items()},
        peaks={s: dict(v) for s, v in check.peaks.items()}, alarm_s=check.alarm_s,
        onset_s=check.onset_s, onset_error_s=check.onset_error_s,
        onset_in_reference=check.since_judged, flagged=dict(check.flagged),
        carried=dict(check.evidence), ways=dict(check.ways))


def _actuators(check: EffortCheck | None) -> ActuatorsPart | None:
    """Each actuator's share of its group's effort against normal logs (null: the model has
    no effort model)."""
    if check is None:
        return None
    return ActuatorsPart(
        summary=check.describe(), judged=check.judged,
        false_alarm_rate=check.false_alarm_rate, alarm_s=check.alarm_s,
        onset_s=check.onset_s, onset_error_s=check.onset_error_s,
        against_alike_logs=check.against_alike_logs, named=tuple(check.named),
        cannot_tell_apart=check.cannot_tell_apart,
        signatures=tuple(SignaturePart(actuator=n, match=m)
                         for n, m in check.matches or check.near_matches),
        not_ruled_out=check.not_ruled_out,
        not_ruled_out_judged_with_logs=check.judged_with_logs,
        shares={a.name: SharePart(
            group=a.group, component=a.component, share=a.share, normal_share=a.normal_share,
            spread=a.spread, departure=a.departure, over_threshold=a.ratio,
            driven_harder=a.driven_harder, judged=a.not_judged is None,
            not_judged=a.not_judged, smallest_rise_shown=a.smallest_rise_shown,
            since_onset=a.since_onset)
        for a in check.actuators})
