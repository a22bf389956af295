"""The diagnosis engine: one log in, one `Diagnosis` out. Rendering never recomputes."""

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.engine.active import ActiveDiagnosis, DmsRun, decide
from auvdiag_cli.engine.closed_loop import replay_closed_loop
from auvdiag_cli.engine.command_check import CommandCheck, check_commands
from auvdiag_cli.engine.completeness import Completeness, completeness_of
from auvdiag_cli.engine.detection import binary_vector, decided_b, detect, first_alarm, look_up
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest, weigh_hypotheses
from auvdiag_cli.engine.ingest import IngestedLog, ingest
from auvdiag_cli.engine.residuals import Matching, match
from auvdiag_cli.engine.segments import (
    ROUTINE_MODE,
    Segment,
    mission_steps,
    segments_of,
    threshold_matrix,
)
from auvdiag_cli.engine.signatures import dms_signature
from auvdiag_cli.engine.start_check import StartCheck, check_start
from auvdiag_cli.engine.substitution import Substitution, substitute
from auvdiag_cli.engine.truth import mission_path, read_missions
from auvdiag_cli.errors import ModelError, UsageError
from auvdiag_cli.numeric import peak
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

ONSET_LOOKBACK_S = 300.0
NOT_JUDGED = "not judged (the model cannot predict it)"
# The candidate the hypotheses name must leave this many times less of its threshold than
# any other candidate.
DECISIVE_MARGIN = 2.0
EPOCH_CLOCK_NS = 10**17     # larger times are Unix time; smaller ones count from boot
PAPER_ASSUMPTIONS = (
    "The environment is steady: a change in how the vehicle moves comes only from its hardware.",
    "At most one sensor or actuator is defective at a time.",
    "A component is either normal or totally defective.",
    "Once defective, a component stays defective until the diagnosis ends.",
)


class Verdict(StrEnum):
    """What a diagnosis concludes; the value is what the reports write."""

    NORMAL = "normal"                  # something was judged and nothing failed
    FAULT = "fault"
    UNDETERMINED = "undetermined"      # nothing could be judged


@dataclass
class SegmentResult:
    segment: Segment
    max_g: dict[str, float]
    b: dict[str, int]
    case: int | None
    components: tuple[str, ...]


@dataclass
class Diagnosis:
    log: Path
    format: str
    vehicle: str
    verdict: Verdict
    component: str | None
    candidates: list[str]
    case: int | None
    b: dict[str, int]
    detected_at_s: float | None
    onset_s: float | None
    segments: list[SegmentResult]
    segment_source: str               # "markers" or "commands"
    substitution: Substitution | None
    model: dict[str, Any]
    window_samples: int
    decision_window_s: float
    sensor_units: dict[str, str]
    notes: list[str] = field(default_factory=list)
    active: ActiveDiagnosis | None = None
    start_ns: int = 0
    mission_legs: list[dict[str, Any]] = field(default_factory=list)
    degradation: Hypothesis | None = None      # a thruster weakened (kind "weakened")
    hypotheses: HypothesisTest | None = None
    # Time histories for reports.
    time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    commands: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    command_names: tuple[str, ...] = ()
    sensor_names: tuple[str, ...] = ()
    matching: Matching | None = None
    thresholds: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    b_series: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    completeness: Completeness | None = None
    not_operating_s: float = 0.0      # time the operating flag excluded from judgement
    not_judged: dict[str, str] = field(default_factory=dict)   # signal -> why not
    command_check: CommandCheck | None = None   # the commands judged against the motion
    start_check: StartCheck | None = None       # the log's start against normal starts


def check_model_fits(model: LoadedModel, profile: Profile, log: Path) -> None:
    """Refuse a model trained for other signals or another step than the profile's."""
    meta = model.metadata
    if model.command_names != profile.command_names or model.sensor_names != profile.sensor_names:
        raise ModelError(
            f"{log}: model {model.path} expects commands {list(model.command_names)} and sensors "
            f"{list(model.sensor_names)}, profile {profile.name!r} gives "
            f"{list(profile.command_names)} and {list(profile.sensor_names)}")
    if abs(float(meta.get("dt_s", -1.0)) - profile.dt_s) > 1e-9:
        raise ModelError(f"{log}: model step {meta.get('dt_s')} s differs from the profile's "
                         f"{profile.dt_s} s")


def diagnose(path: Path, profile: Profile, model: LoadedModel,
             companions: Sequence[Path] = (), mission: Path | None = None) -> Diagnosis:
    """Diagnose the log at ``path`` (raises LogError / ModelError when it cannot).

    ``companions`` are other logs of the same vehicle and day whose Diagnosis Motion
    Sequences may decide between candidates (active diagnosis). ``mission`` is the mission
    plan (default: NAME.mission.json beside the log, when there is one), used to replay
    Substituting Control in closed loop."""
    check_model_fits(model, profile, path)
    legs = _mission_legs(mission or mission_path(path), explicit=mission is not None)
    main = ingest(path, profile)
    runs: list[tuple[DmsRun, int]] = []
    notes: list[str] = []
    for companion in companions:
        other = ingest(companion, profile)
        problem = _companion_problem(main, other)
        if problem is not None:
            notes.append(f"companion log {companion} ignored: {problem}")
            continue
        result = diagnose_ingested(other, profile, model)
        runs += [(run, result.start_ns) for run in dms_runs(result)]
        notes.append(f"companion log {companion}: {len(dms_runs(result))} DMS run(s)")
    diagnosis = diagnose_ingested(main, profile, model, runs, legs)
    diagnosis.notes += notes
    return diagnosis


def _mission_legs(path: Path, explicit: bool) -> list[dict[str, Any]]:
    if not path.is_file():
        if explicit:
            raise UsageError(f"{path}: no such mission plan")
        return []
    try:
        return read_missions(path)
    except (OSError, ValueError) as error:
        raise UsageError(f"{path}: unreadable mission plan: {error}") from None


def _companion_problem(main: IngestedLog, other: IngestedLog) -> str | None:
    """Why another log cannot speak for this vehicle's state, or None."""
    a, b = main.signals, other.signals
    if a.start_ns < b.end_ns and b.start_ns < a.end_ns:
        return "it overlaps this log in time (one vehicle cannot fly two dives at once)"
    if min(a.start_ns, b.start_ns) > EPOCH_CLOCK_NS:
        day_a = datetime.fromtimestamp(a.start_ns / 1e9, UTC).date()
        day_b = datetime.fromtimestamp(b.start_ns / 1e9, UTC).date()
        if day_a != day_b:
            return f"recorded on {day_b}, this log on {day_a}"
    return None


def dms_runs(diagnosis: Diagnosis) -> list[DmsRun]:
    """The log's DMS segments with their outcome, in absolute time."""
    return [DmsRun(str(diagnosis.log), r.segment.name,
                   diagnosis.start_ns + round(r.segment.start_s * 1e9),
                   diagnosis.start_ns + round(r.segment.end_s * 1e9), r.b)
            for r in diagnosis.segments if r.segment.mode == ROUTINE_MODE]


def diagnose_ingested(log: IngestedLog, profile: Profile, model: LoadedModel,
                      companion_runs: Sequence[tuple[DmsRun, int]] = (),
                      mission_legs: Sequence[dict[str, Any]] = ()) -> Diagnosis:
    frame, signals = log.frame, log.signals
    full_scale = model.metadata.get("full_scale", profile.full_scales)
    window = int(model.metadata.get("window_samples", profile.window_samples))
    judged = _with_model_thresholds(profile, model)
    segments = segments_of(log, judged)
    # Every DMS is a test of its own: the replay starts afresh from the measured state.
    dms_starts = [int(np.searchsorted(frame.time_s, s.start_s)) for s in segments
                  if s.mode == ROUTINE_MODE]
    matching = match(model, frame, full_scale, window, dms_starts)
    thresholds = threshold_matrix(segments, frame.time_s, frame.sensor_names)
    b_series = binary_vector(matching.g_percent, thresholds)
    not_judged = not_judged_signals(model)
    for i, name in enumerate(frame.sensor_names):
        if name in not_judged:
            b_series[:, i] = 0          # a signal the model cannot predict raises no alarm
    scales = np.asarray([full_scale[n] for n in frame.sensor_names])
    residual = np.abs(matching.measured - matching.modelled) / scales
    decision = round(profile.decision_window_s / profile.dt_s)
    detection = detect(b_series, residual, thresholds, frame.sensor_names, decision,
                       round(ONSET_LOOKBACK_S / profile.dt_s), [*frame.restarts, *dms_starts])
    notes = list(signals.notes) + frame.notes
    notes += [f"gap in {gap.signal} from {gap.start_s:.1f} s to {gap.end_s:.1f} s "
              "(not interpolated)" for gap in frame.gaps]
    diagnosis = Diagnosis(
        log=signals.path, format=signals.format, vehicle=profile.name, verdict=Verdict.NORMAL,
        component=None, candidates=[], case=_normal_case(profile),
        b={name: 0 for name in frame.sensor_names}, detected_at_s=None, onset_s=None,
        segments=_segment_results(segments, frame.time_s, matching, b_series,
                                  frame.sensor_names, profile, decision),
        segment_source="markers" if signals.markers else "commands",
        substitution=None, model=model.identity, window_samples=window,
        decision_window_s=profile.decision_window_s,
        sensor_units={s.name: s.unit for s in profile.sensors}, notes=notes,
        time_s=frame.time_s, commands=frame.commands, command_names=frame.command_names,
        sensor_names=frame.sensor_names, matching=matching, thresholds=thresholds,
        b_series=b_series, start_ns=signals.start_ns, mission_legs=list(mission_legs),
        completeness=completeness_of(signals),
        not_operating_s=round(float((~frame.operating).sum()) * frame.dt_s, 3),
        not_judged=not_judged)
    if model.skill is None:
        diagnosis.notes.append("the model has no skill scores (trained before they were "
                               "measured): every signal is judged; 'auvdiag score' measures them")
    diagnosis.command_check = _check_commands(log, segments, profile, model, diagnosis.notes)
    diagnosis.start_check = check_start(model.metadata.get("start_state"), frame.commands,
                                        frame.sensors, frame.time_s, frame.sensor_names,
                                        frame.dt_s)
    check, start = diagnosis.command_check, diagnosis.start_check
    if len(not_judged) == len(frame.sensor_names):
        diagnosis.notes.append("no signal is judged: the model cannot predict any of them")
        if (check is not None and check.judged) or start.judged:
            _apply_other_evidence(diagnosis, check, start, profile, model)
            return diagnosis
        diagnosis.verdict, diagnosis.case = Verdict.UNDETERMINED, None
        return diagnosis
    if detection is None:
        _apply_other_evidence(diagnosis, check, start, profile, model)
    if detection is not None:
        _apply_detection(diagnosis, detection.b, frame.time_s[detection.alarm_index],
                         frame.time_s[detection.onset_index], profile, model)
        test = weigh_hypotheses(model, profile, frame, matching, thresholds,
                                detection.onset_index, dms_starts, list(not_judged))
        diagnosis.hypotheses = test
        weak = next((h for h in test.ranked if h.is_actuator), None)
        if len(diagnosis.candidates) > 1:
            own = [(run, signals.start_ns) for run in dms_runs(diagnosis)]
            _apply_active_diagnosis(diagnosis, [*own, *companion_runs], profile, model)
        elif diagnosis.substitution is not None:
            if weak is not None and weak.explains:
                _apply_weakened_thruster(diagnosis, weak, profile)
        elif not diagnosis.candidates:
            _name_by_hypotheses(diagnosis, test, profile, model)
    return diagnosis


def _check_commands(log: IngestedLog, segments: list[Segment], profile: Profile,
                    model: LoadedModel, notes: list[str]) -> CommandCheck | None:
    """The commands against the motion, over the steps driven in closed loop or by a pilot
    (not the DMS runs, whose commands are fixed)."""
    relations = model.relations
    if relations is None:
        why = (model.metadata.get("command_relations") or {}).get("refused")
        notes.append("commands not judged against the motion: " + (
            why or "the model has no command relations ('auvdiag relate' learns them)"))
        return None
    frame = log.frame
    return check_commands(relations, profile, frame.commands, frame.sensors,
                          mission_steps(segments, frame.time_s, frame.operating), frame.time_s)


def _apply_other_evidence(diagnosis: Diagnosis, check: CommandCheck | None,
                          start: StartCheck, profile: Profile, model: LoadedModel) -> None:
    """The replay raised no alarm: a sensor that read wrong from the start, or an actuator
    driven harder than the motion needs, still makes the verdict."""
    if start.off:
        _apply_start_alarm(diagnosis, start, profile, model)
    elif check is not None and check.alarm_s is not None:
        _apply_command_alarm(diagnosis, check, profile, model)


def _apply_start_alarm(diagnosis: Diagnosis, start: StartCheck, profile: Profile,
                       model: LoadedModel) -> None:
    """The replay starts from the measured state and takes a wrong start reading as the
    truth; the sensors that started away from where normal logs start are the candidates."""
    diagnosis.verdict, diagnosis.case = Verdict.FAULT, None
    diagnosis.onset_s, diagnosis.detected_at_s = 0.0, start.at_s
    diagnosis.candidates = list(dict.fromkeys(
        s.component for s in profile.sensors if s.name in start.off))
    diagnosis.notes.append("found at the start of the log: "
                           + start.describe(diagnosis.sensor_units))
    if len(diagnosis.candidates) == 1:
        _name_component(diagnosis, diagnosis.candidates[0], profile, model)


def _apply_command_alarm(diagnosis: Diagnosis, check: CommandCheck, profile: Profile,
                         model: LoadedModel) -> None:
    """The motion looks normal (or cannot be judged) but an actuator works harder than the
    motion needs: a weakened actuator whose loss the controller makes up for."""
    diagnosis.verdict, diagnosis.case = Verdict.FAULT, None
    diagnosis.detected_at_s, diagnosis.onset_s = check.alarm_s, check.onset_s
    # A sensor reading the motion wrongly also makes the controller push harder; the motion
    # model rules that out only for the sensors it judges.
    unjudged = [s.component for s in profile.sensors if s.name in diagnosis.not_judged]
    diagnosis.candidates = list(dict.fromkeys([*check.named, *unjudged])) if check.named else []
    note = f"found in the commands, not the motion: {check.describe()}"
    if len(check.named) > 1:
        note += "; these actuators act alike on the vehicle and cannot be told apart from it"
    if check.named and unjudged:
        note += ("; a misreading " + " or ".join(dict.fromkeys(unjudged)) + " (not judged by "
                 "the motion model) would look the same")
    diagnosis.notes.append(note)
    if len(diagnosis.candidates) == 1:
        _name_component(diagnosis, diagnosis.candidates[0], profile, model)


def _name_by_hypotheses(diagnosis: Diagnosis, test: HypothesisTest, profile: Profile,
                        model: LoadedModel) -> None:
    """No row of the pattern table names the component (or there is no table): the
    hypothesis that explains the log does, when one does."""
    best, runner_up, margin = test.best, test.runner_up, test.margin
    if not best.explains:
        raised = ", ".join(k for k, v in diagnosis.b.items() if v)
        diagnosis.notes.append(f"anomaly on {raised}: no single-component fault explains it "
                               f"(the closest, {best.describe()}, leaves g at "
                               f"{best.peak_g_ratio:.0%} of its threshold)")
        return
    beside = ("" if runner_up is None or margin is None else
              f"; runner-up {runner_up.describe()} ({runner_up.peak_g_ratio:.0%}, "
              f"{margin:.1f}x the best)")
    diagnosis.notes.append(f"named by the hypothesis test: {best.describe()} explains the log "
                           f"(g then stays at {best.peak_g_ratio:.0%} of its threshold at "
                           f"most){beside}")
    diagnosis.candidates = [best.component]
    if best.kind == "weakened":
        diagnosis.degradation = best
    _name_component(diagnosis, best.component, profile, model)


def _apply_weakened_thruster(diagnosis: Diagnosis, weak: Hypothesis,
                             profile: Profile) -> None:
    table_says = diagnosis.component
    diagnosis.component, diagnosis.candidates = weak.component, [weak.component]
    diagnosis.substitution = None
    explained = (f"the pattern table reads b as {table_says}, but the log is explained by "
                 f"{weak.component} ")
    if weak.thrust_fraction == 0.0:
        # A thruster dying in a turn or at low speed raises one bit before the other: the
        # decision window saw only that one, and it is a sensor's row.
        row = next((r for r in profile.pattern if weak.component in r.components), None)
        diagnosis.case = None if row is None else row.case
        diagnosis.notes.append(
            explained + f"dead from the onset (g then stays at {weak.peak_g_ratio:.0%} of its "
            "threshold at most): its failure raised the bits of its row one after the other")
        return
    diagnosis.degradation = weak
    diagnosis.notes.append(
        explained + f"giving {weak.thrust_fraction:.0%} of its thrust from the onset "
        f"(g then stays at {weak.peak_g_ratio:.0%} of its threshold at most): a partial "
        "failure, which the paper's table (assumption 3) does not describe")


def _apply_active_diagnosis(diagnosis: Diagnosis, runs: list[tuple[DmsRun, int]],
                            profile: Profile, model: LoadedModel) -> None:
    assert diagnosis.onset_s is not None
    onset_ns = diagnosis.start_ns + round(diagnosis.onset_s * 1e9)
    active = decide(diagnosis.candidates, onset_ns, runs, profile)
    diagnosis.active = active
    if active.conflict:
        diagnosis.notes.append("the DMS runs contradict each other (more than one fault?); "
                               "all candidates kept")
    if len(active.candidates) > 1:
        _narrow_by_predicted_signatures(diagnosis, active, onset_ns, runs, profile, model)
    if len(active.candidates) > 1 and diagnosis.hypotheses is not None:
        _narrow_by_hypotheses(diagnosis, active, diagnosis.hypotheses)
    diagnosis.candidates = active.candidates
    if len(active.candidates) == 1:
        _name_component(diagnosis, active.candidates[0], profile, model)


def _narrow_by_hypotheses(diagnosis: Diagnosis, active: ActiveDiagnosis,
                          test: HypothesisTest) -> None:
    """Among the candidates the DMS runs leave, the one whose failure explains the log when
    no other candidate's does, by DECISIVE_MARGIN at least (e.g. which thruster died on a
    plain mission: the table reads both the same)."""
    best = {c: min((h for h in test.ranked if h.component == c),
                   key=lambda h: h.peak_g_ratio, default=None) for c in active.candidates}
    scored = sorted((h for h in best.values() if h is not None), key=lambda h: h.peak_g_ratio)
    if len(scored) < 2 or not scored[0].explains or scored[1].explains:
        return
    margin = scored[1].peak_g_ratio / max(scored[0].peak_g_ratio, 1e-9)
    if margin < DECISIVE_MARGIN:
        return
    winner = scored[0]
    diagnosis.notes.append(
        f"the pattern table reads b as {' or '.join(active.candidates)}; replayed from the "
        f"onset, {winner.describe()} explains the log (g at most {winner.peak_g_ratio:.0%} of "
        f"its threshold) and {scored[1].describe()} does not ({scored[1].peak_g_ratio:.0%})")
    active.candidates, active.recommended_dms = [winner.component], []
    if winner.kind == "weakened":
        diagnosis.degradation = winner


def _narrow_by_predicted_signatures(diagnosis: Diagnosis, active: ActiveDiagnosis,
                                    onset_ns: int, runs: list[tuple[DmsRun, int]],
                                    profile: Profile, model: LoadedModel) -> None:
    """Where moving or not moving a component cannot separate the candidates (a thruster
    and the sensor of the motion it drives), the model can: it predicts each candidate's b
    on every DMS run made wholly with the fault present. A run that stayed quiet (b = 0)
    clears the candidates whose failure would have shown on it; a run that raised an alarm
    clears those whose failure would not have. Which bits an alarm raises is left out: near
    a threshold the model cannot call single bits reliably. Never all are cleared."""
    kept = list(active.candidates)
    for run, _ in runs:
        if run.start_ns < onset_ns or run.name not in profile.dms:
            continue
        alarm = any(run.b.values())
        predicted = {c: any(dms_signature(model, profile, run.name, c).values()) for c in kept}
        agreeing = [c for c in kept if predicted[c] == alarm]
        if agreeing and len(agreeing) < len(kept):
            seen = "".join(str(v) for v in run.b.values())
            dropped = [c for c in kept if c not in agreeing]
            would = "would have shown on it" if not alarm else "would not have shown on it"
            diagnosis.notes.append(f"{run.name} in {run.log} gave b = {seen}: the model says "
                                   f"a failed {' or '.join(dropped)} {would}")
            kept = agreeing
    active.candidates = kept
    # The DMSs on which the remaining candidates' failures look different decide next time.
    active.recommended_dms = [] if len(kept) == 1 else [
        name for name in profile.dms
        if len({tuple(dms_signature(model, profile, name, c).values()) for c in kept}) > 1]


def not_judged_signals(model: LoadedModel) -> dict[str, str]:
    """The signals the model has no skill for, with the reason reports print."""
    signals = model.metadata.get("skill", {}).get("signals", {})
    needed = model.metadata.get("skill", {}).get("judged_from_samples", 0)
    reasons = {}
    for name in model.unskilled:
        record = signals[name]
        if record.get("samples", needed) < needed:
            reasons[name] = (f"not judged (too little held-out data to measure the model's "
                             f"skill: {record['samples']} samples)")
        else:
            skill = record.get("skill")
            reasons[name] = NOT_JUDGED + ("" if skill is None else f" (skill {skill:.2f})")
    return reasons


def _with_model_thresholds(profile: Profile, model: LoadedModel) -> Profile:
    """Thresholds calibrated into the model override the profile's defaults."""
    calibrated = model.metadata.get("thresholds")
    if not calibrated:
        return profile
    return replace(profile, thresholds={**profile.thresholds, **calibrated})


def _normal_case(profile: Profile) -> int | None:
    row = look_up(profile.pattern, {s.name: 0 for s in profile.sensors})
    return None if row is None else row.case


def _apply_detection(diagnosis: Diagnosis, b: dict[str, int], alarm_s: float, onset_s: float,
                     profile: Profile, model: LoadedModel) -> None:
    diagnosis.verdict = Verdict.FAULT
    diagnosis.b = b
    diagnosis.detected_at_s = round(float(alarm_s), 3)
    diagnosis.onset_s = round(float(onset_s), 3)
    row = look_up(profile.pattern, b)
    diagnosis.case = None if row is None else row.case
    candidates = (list(row.components) if row is not None
                  else _predicted_on_dms(diagnosis, b, alarm_s, profile, model))
    if not candidates and not profile.pattern:
        diagnosis.notes.append(f"the profile has no pattern table to read b = {b} in")
    elif not candidates:
        diagnosis.notes.append(f"b = {b} fits no row of the pattern table: more than one fault, "
                               "or one the table does not describe")
    diagnosis.candidates = candidates
    if len(candidates) == 1:
        _name_component(diagnosis, candidates[0], profile, model)


def _predicted_on_dms(diagnosis: Diagnosis, b: dict[str, int], alarm_s: float,
                      profile: Profile, model: LoadedModel) -> list[str]:
    """The table describes the mission; a DMS moves the vehicle otherwise, so a failure can
    show there with a b of its own. When the alarm came on a DMS, the candidates are the
    components whose failure, the model predicts, raises one of the same bits on it (the
    DMS runs that follow narrow them down)."""
    segment = next((r.segment for r in diagnosis.segments
                    if r.segment.mode == ROUTINE_MODE and r.segment.name in profile.dms
                    and r.segment.start_s <= alarm_s <= r.segment.end_s), None)
    if segment is None:
        return []
    components = [c.component for c in profile.commands] + [s.component
                                                            for s in profile.sensors]
    matching = [c for c in components
                if any(b[k] and v for k, v in
                       dms_signature(model, profile, segment.name, c).items())]
    if matching:
        bits = "".join(str(v) for v in b.values())
        diagnosis.notes.append(f"b = {bits} on {segment.name} fits no row of the pattern table "
                               "(which describes the mission); the model predicts an alarm on "
                               f"one of these signals on {segment.name} for: "
                               f"{', '.join(matching)}")
    return matching


def _name_component(diagnosis: Diagnosis, component: str, profile: Profile,
                    model: LoadedModel) -> None:
    """The verdict names one component; a failed sensor gets Substituting Control."""
    diagnosis.component = component
    sensor = next((s for s in profile.sensors if s.component == component), None)
    matching = diagnosis.matching
    if sensor is not None and diagnosis.onset_s is not None and matching is not None:
        errors = model.metadata.get("heldout_error", {}).get("rms", {})
        diagnosis.substitution = substitute(
            diagnosis.log, sensor, diagnosis.sensor_names, diagnosis.time_s, matching.measured,
            matching.modelled, diagnosis.onset_s, profile.navigation, errors.get(sensor.name))
        if profile.controller is not None and diagnosis.mission_legs:
            diagnosis.substitution.closed_loop = replay_closed_loop(
                model, profile.controller, diagnosis.sensor_names, diagnosis.command_names,
                diagnosis.time_s, diagnosis.commands, matching.measured, diagnosis.onset_s,
                diagnosis.mission_legs, profile.dt_s)


def _segment_results(segments: list[Segment], time_s: np.ndarray, matching: Matching,
                     b_series: np.ndarray, sensor_names: tuple[str, ...], profile: Profile,
                     decision_steps: int) -> list[SegmentResult]:
    """Each segment's peak g, and its b read as the whole log's is: at its first alarm."""
    results = []
    for segment in segments:
        inside = (time_s >= segment.start_s) & (time_s <= segment.end_s)
        g = matching.g_percent[inside]
        max_g = {name: round(peak(g[:, i]), 3) for i, name in enumerate(sensor_names)}
        rows = b_series[inside]
        alarm = first_alarm(rows)
        bits = np.zeros(len(sensor_names), bool) if alarm is None else decided_b(
            rows, alarm, decision_steps)
        b = {name: int(bits[i]) for i, name in enumerate(sensor_names)}
        row = look_up(profile.pattern, b)
        results.append(SegmentResult(segment, max_g, b, None if row is None else row.case,
                                     () if row is None else row.components))
    return results
