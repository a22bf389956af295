"""The diagnosis engine: one log in, one `Diagnosis` out. Rendering never recomputes."""

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.active import DmsRun
from auvdiag_cli.engine.change_check import ChangeCheck, check_change
from auvdiag_cli.engine.change_columns import (
    change_judged,
    change_names,
    change_residual,
    left_by_the_change_test,
    loop_names,
)
from auvdiag_cli.engine.change_signatures import below_only, signature_only, thresholded
from auvdiag_cli.engine.change_suspects import beyond_the_replay, names_a_mover
from auvdiag_cli.engine.command_check import CommandCheck, check_commands
from auvdiag_cli.engine.completeness import completeness_of
from auvdiag_cli.engine.detection import (
    Detection,
    binary_vector,
    decided_b,
    detect,
    first_alarm,
    look_up,
    normal_case,
)
from auvdiag_cli.engine.effort_check import EffortCheck, check_effort
from auvdiag_cli.engine.flat_signals import held_at, not_judged_flat
from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.hypotheses import weigh_hypotheses
from auvdiag_cli.engine.ingest import IngestedLog, ingest
from auvdiag_cli.engine.isolation import isolate
from auvdiag_cli.engine.judging import Judging, nothing_judged, skilled
from auvdiag_cli.engine.log_clock import clock_note, utc_offset_ns, utc_start_ns
from auvdiag_cli.engine.missions import MissionLeg, mission_path, read_missions
from auvdiag_cli.engine.onset_dating import sharpest_onset
from auvdiag_cli.engine.other_alarms import apply_change_alarm, apply_other_evidence
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.residuals import Matching, match
from auvdiag_cli.engine.results import (
    Diagnosis,
    Finding,
    Observations,
    SegmentResult,
    Verdict,
    dms_runs,
    utc_day,
)
from auvdiag_cli.engine.segments import (
    ROUTINE_MODE,
    Segment,
    mission_steps,
    segments_of,
    threshold_matrix,
)
from auvdiag_cli.engine.slight_alarm import within_what_it_knows
from auvdiag_cli.engine.start_check import check_start
from auvdiag_cli.numeric import peak
from auvdiag_cli.vehicle.actuators import SET_POINT, outing
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import CompanionError, ModelError
from models.fast import new_replay_budget
from models.store import LoadedModel

ONSET_LOOKBACK_S = 300.0
# A profile changed since its model was trained, or another vehicle's model: train again.
REFIT = "train the model with this profile, or diagnose with the profile it was trained with"


def check_model_fits(model: LoadedModel, profile: Profile, log: Path) -> None:
    """Refuse a model trained for other signals or another step than the profile's."""
    if model.command_names != profile.command_names or model.sensor_names != profile.sensor_names:
        raise ModelError(
            f"{log}: model {model.path} expects commands {list(model.command_names)} and sensors "
            f"{list(model.sensor_names)}, profile {profile.name!r} gives "
            f"{list(profile.command_names)} and {list(profile.sensor_names)}: {REFIT}")
    if model.input_names != profile.input_names:
        raise ModelError(
            f"{log}: model {model.path} is driven by the measured inputs "
            f"{list(model.input_names) or 'none'}, profile {profile.name!r} gives "
            f"{list(profile.input_names) or 'none'}: {REFIT}")
    if abs(model.card.dt_s - profile.dt_s) > 1e-9:
        raise ModelError(f"{log}: model step {model.card.dt_s} s differs from the profile's "
                         f"{profile.dt_s} s: {REFIT}")
    window = model.card.window_samples or profile.window_samples
    stride = model.card.change_stride
    if stride is not None and window % stride:
        raise ModelError(f"{log}: model {model.path}: its change test's stride_steps {stride} "
                         f"does not divide its window of {window} steps: calibrate it again")


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
    return replace(diagnosis, notes=(*diagnosis.notes, *notes))


def _mission_legs(path: Path, explicit: bool) -> tuple[MissionLeg, ...]:
    if not path.is_file():
        if explicit:
            raise CompanionError(f"{path}: no such mission plan")
        return ()
    try:
        return read_missions(path)
    except (OSError, ValueError, TypeError) as error:
        raise CompanionError(f"{path}: unreadable mission plan: {error}") from None


def _companion_problem(main: IngestedLog, other: IngestedLog) -> str | None:
    """Why another log cannot speak for this vehicle's state, or None."""
    a, b = main.signals, other.signals
    if a.start_ns < b.end_ns and b.start_ns < a.end_ns:
        return "it overlaps this log in time (one vehicle cannot fly two dives at once)"
    day_a, day_b = utc_day(utc_start_ns(a)), utc_day(utc_start_ns(b))
    if day_a and day_b and day_a != day_b:
        return f"recorded on {day_b}, this log on {day_a}"
    return None


def _calibrated_on_another_day(days: Sequence[str], start_ns: int) -> list[str]:
    """A note where every normal log the thresholds were set on is of one day and this log
    of another: that day's wind, sea or payload is all they have seen."""
    day = utc_day(start_ns)
    if len(days) != 1 or day is None or day == days[0]:
        return []
    return [f"the thresholds were set on normal logs of one day ({days[0]}) and this log is "
            f"of {day}: another day's conditions (wind or current, sea state, payload) may "
            "move it further than they allow, so an alarm here is less certain; calibrate "
            "on normal logs of several days"]


def _inputs_held(log: IngestedLog, model: LoadedModel) -> IngestedLog:
    """The log with each measured input it never fed, and each one no log the model was
    trained on fed (it never learnt how it acts), held at its typical value on the model's
    training logs (`flat_signals.held_at`)."""
    frame = log.frame
    unlearnt = [i for i in model.card.inputs
                if not i.fed and i.name in frame.input_names and i.name not in frame.flat_inputs]
    if not frame.flat_inputs and not unlearnt:
        return log
    typical = {i.name: i.typical for i in model.card.inputs}
    held = held_at(frame.inputs, frame.input_names,
                   {**frame.flat_inputs, **{i.name: "" for i in unlearnt}}, typical)
    notes = [f"{i.name}: no log the model was trained on fed it (one value throughout), so "
             f"it never learnt how it acts: held at {i.typical:g}, as there, not read from this "
             "log; train on logs that feed it" for i in unlearnt]
    return IngestedLog(log.signals, replace(frame, inputs=held, notes=[*frame.notes, *notes]))


@dataclass(frozen=True)
class _Replayed:
    """A log replayed by the model: what every judge starts from."""

    log: IngestedLog                  # its measured inputs held where it never fed them
    judging: Judging
    segments: list[Segment]
    dms_starts: list[int]             # where the replay starts afresh (each DMS run)
    matching: Matching
    change_errors: np.ndarray         # what the change test judges


def _replay(log: IngestedLog, profile: Profile, model: LoadedModel) -> _Replayed:
    new_replay_budget()
    log = _inputs_held(log, model)
    frame = log.frame
    judging = Judging.of(model, profile).without(not_judged_flat(frame.flat))
    segments = segments_of(log, judging.profile)
    # Every DMS is a test of its own: the replay starts afresh from the measured state.
    dms_starts = [int(np.searchsorted(frame.time_s, s.start_s)) for s in segments
                  if s.mode == ROUTINE_MODE]
    matching = match(model, frame, judging.full_scale, judging.window, dms_starts)
    return _Replayed(log, judging, segments, dms_starts, matching, change_residual(
        model, frame, matching, [*frame.restarts, *dms_starts]))


def change_errors_of(log: IngestedLog, profile: Profile, model: LoadedModel
                     ) -> tuple[np.ndarray, tuple[str, ...]]:
    """What the change test judges on a log, without the rest of a diagnosis, and the
    signals set aside there (never fed)."""
    replayed = _replay(log, profile, model)
    return replayed.change_errors, tuple(sorted(replayed.judging.set_aside))


def diagnose_ingested(log: IngestedLog, profile: Profile, model: LoadedModel,
                      companion_runs: Sequence[tuple[DmsRun, int]] = (),
                      mission_legs: Sequence[MissionLeg] = ()) -> Diagnosis:
    replayed = _replay(log, profile, model)
    log, judging, segments, dms_starts, matching, change_errors = (
        replayed.log, replayed.judging, replayed.segments, replayed.dms_starts,
        replayed.matching, replayed.change_errors)
    frame, signals = log.frame, log.signals
    not_judged, decision = judging.not_judged, judging.decision_steps
    thresholds = threshold_matrix(segments, frame.time_s, frame.sensor_names)
    b_series = binary_vector(matching.g_percent, thresholds)
    b_series[:, ~judging.judged_mask] = 0   # a signal the model cannot predict raises no alarm
    residual = np.abs(matching.measured - matching.modelled) / judging.scales
    detection = detect(b_series, residual, thresholds, frame.sensor_names, decision,
                       round(ONSET_LOOKBACK_S / profile.dt_s), [*frame.restarts, *dms_starts])
    notes = list(signals.notes) + frame.notes + [
        f"gap in {gap.signal} from {gap.start_s:.1f} s to {gap.end_s:.1f} s (not "
        "interpolated)" for gap in frame.gaps]
    if model.skill is None:
        notes.append("the model has no skill scores (trained before they were measured): "
                     "every signal is judged; 'auvdiag score' measures them")
    utc_offset = utc_offset_ns(signals)
    notes += clock_note(utc_offset) + _calibrated_on_another_day(
        model.card.calibration_days, signals.start_ns + utc_offset)
    change_check = _check_change(change_errors, judging, frame, notes)
    seen = Observations(
        log=signals.path, format=signals.format, vehicle=profile.name,
        segments=tuple(_segment_results(segments, frame.time_s, matching, b_series,
                                        frame.sensor_names, profile, decision)),
        segment_source="markers" if signals.markers else "commands",
        model=model.identity, window_samples=judging.window,
        decision_window_s=profile.decision_window_s,
        sensor_units={**{c.name: c.unit for c in profile.commands if c.unit},
                      **{s.name: s.unit for s in profile.sensors}},
        histories=Histories(frame.time_s, frame.commands, frame.command_names,
                            frame.sensor_names, matching, thresholds, b_series,
                            change_errors, tuple(change_names(model))),
        start_ns=signals.start_ns, utc_offset_ns=utc_offset, mission_legs=tuple(mission_legs),
        completeness=completeness_of(signals),
        not_operating_s=round(frame.not_operating_s, 3),
        not_judged={**not_judged, **left_by_the_change_test(change_check, judging)},
        set_aside=tuple(sorted(judging.set_aside)),
        command_check=_check_commands(log, segments, judging, notes),
        start_check=check_start(model.card.start_state, frame.commands, frame.sensors,
                                frame.time_s, frame.sensor_names, frame.dt_s, outing(
                                    [*(c.kind for c in profile.commands),
                                     *(a.kind for a in profile.actuators)])),
        effort_check=_check_effort(log, segments, judging, notes),
        change_check=change_check,
        set_points=tuple(c.name for c in profile.commands if c.kind == SET_POINT),
        autopilot=log.autopilot_said)
    normal = Finding(verdict=Verdict.NORMAL, b={name: 0 for name in frame.sensor_names},
                     case=normal_case(profile.pattern, profile.sensor_names),
                     notes=tuple(notes))
    finding = _conclude(seen, normal, detection, judging, log, matching, thresholds,
                        dms_starts, companion_runs)
    return Diagnosis.of(seen, sharpest_onset(
        within_what_it_knows(finding, normal, seen, judging, frame, profile), seen))


def _conclude(seen: Observations, normal: Finding, detection: Detection | None,
              judging: Judging, log: IngestedLog, matching: Matching, thresholds: np.ndarray,
              dms_starts: list[int], companion_runs: Sequence[tuple[DmsRun, int]]
              ) -> Finding:
    """The finding: from the replay's alarm where it raised one, else from the checks."""
    others = (seen.command_check, seen.start_check, seen.effort_check)
    # Signals judged only against the log's own beginning are judged, by the change test.
    change = seen.change_check
    if len(judging.not_judged) == len(seen.histories.sensor_names) and not (
            change is not None and change.judged):
        normal = normal.noted(nothing_judged(judging, None if change is None
                                             else change.describe()))
        if any(other is not None and other.judged for other in others):
            return apply_other_evidence(seen, normal, judging)
        return replace(normal, verdict=Verdict.UNDETERMINED, case=None)
    frame = log.frame
    if change is not None and change.alarm_s is not None and change.onset_s is not None and (
            detection is None or change.alarm_s < frame.time_s[detection.alarm_index]):
        if names_a_mover(change, judging.profile) or beyond_the_replay(change, judging):
            return apply_change_alarm(seen, normal, change, judging, _healthy_replay(
                judging, frame, change.onset_s, dms_starts))
        # The change came first: its b and times, named as the replay's alarm would be.
        b = {name: int(name in change.changed) for name in frame.sensor_names}
        onset = int(np.searchsorted(frame.time_s, change.onset_s))
        test = weigh_hypotheses(judging, frame, matching, thresholds, onset, dms_starts,
                                seen.effort_check)
        return isolate(seen, normal.noted(f"found by the change test: {change.describe()}"),
                       b, change.alarm_s, change.onset_s, test, companion_runs, judging)
    if detection is None:
        return apply_other_evidence(seen, normal, judging)
    test = weigh_hypotheses(judging, frame, matching, thresholds, detection.onset_index,
                            dms_starts, seen.effort_check)
    return isolate(seen, normal, detection.b, frame.time_s[detection.alarm_index],
                   frame.time_s[detection.onset_index], test, companion_runs, judging)


def _healthy_replay(judging: Judging, frame: AlignedFrame, onset_s: float,
                    dms_starts: list[int]) -> np.ndarray:
    """The model of the healthy vehicle replayed from the measured state at the onset (and
    after it, every horizon of the model): what the vehicle would have done had nothing
    failed, which the failure's effect is measured against."""
    onset = int(np.searchsorted(frame.time_s, onset_s))
    return match(judging.model, frame, judging.full_scale, judging.window,
                 [*dms_starts, onset], since=onset).modelled


def _check_change(residual: np.ndarray, judging: Judging, frame: AlignedFrame,
                  notes: list[str]) -> ChangeCheck | None:
    """The log against its own beginning, for the signals the test judges
    (`change_judged`) that calibrate set a threshold for (None: no such threshold)."""
    profile, model = judging.profile, judging.model
    names = change_names(model)
    in_play = [name for name in change_judged(model, skilled(model, profile))
               if name not in judging.set_aside]
    judged = thresholded(profile.actuators, profile.sensors, in_play)
    missing = sorted(frame.flat_inputs)
    measured = [name for name in missing if name in model.card.change_unfed]
    thresholds = {statistic: {name: value for name, value in limits.items() if name in judged}
                  for statistic, limits in model.card.change_thresholds_without(
                      measured).items()}
    if not any(thresholds.values()):
        return None
    ahead = model.card.ahead
    if measured:
        notes.append(f"change test: {', '.join(measured)} not fed in this log: judged "
                     "against the thresholds calibrate set on its normal logs replayed "
                     "without it, where higher")
    unmeasured = [name for name in missing if name not in measured]
    if unmeasured and ahead is not None and ahead.inputs:
        notes.append(f"change test: {', '.join(unmeasured)} not "
                     "fed in this log, though its predictor a moment ahead reads it as part "
                     "of the state: it predicts this log with less than the logs its "
                     "thresholds were set on had, and an alarm here is less certain")
    return check_change(residual, names, thresholds, frame.time_s,
                        judging.window, profile.dt_s, profile.actuators,
                        model.card.change_stride, model.card.change_way_scales,
                        loop_names(model), signature_only(profile.sensors) & set(in_play),
                        below_only(profile.sensors))


def _check_commands(log: IngestedLog, segments: list[Segment], judging: Judging,
                    notes: list[str]) -> CommandCheck | None:
    """The commands against the motion, over the steps driven in closed loop or by a pilot
    (not the DMS runs, whose commands are fixed)."""
    profile, model = judging.profile, judging.model
    relations = model.relations
    if relations is None:
        why = model.card.relations_refused
        notes.append("commands not judged against the motion: " + (
            why or "the model has no command relations ('auvdiag relate' learns them)"))
        return None
    frame = log.frame
    return check_commands(relations, profile, frame.commands, frame.sensors,
                          mission_steps(segments, frame.time_s, frame.operating), frame.time_s)


def _check_effort(log: IngestedLog, segments: list[Segment], judging: Judging,
                  notes: list[str]) -> EffortCheck | None:
    """Each actuator's share of its group's effort over the steps a controller or a pilot
    drove (not the DMS runs)."""
    profile, model = judging.profile, judging.model
    effort = model.effort
    if effort is None:
        if profile.effort_groups:
            why = model.card.effort_refused
            notes.append("effort shares not judged: " + (
                why or "the model has no effort model (train it again to learn one)"))
        return None
    frame = log.frame
    return check_effort(effort, profile, frame.efforts,
                        mission_steps(segments, frame.time_s, frame.operating), frame.time_s)


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
