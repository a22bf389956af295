"""Naming the component once something is found: the pattern table's row, the hypothesis
test, the DMS runs (active diagnosis), a weakened thruster, the start and command checks;
and Substituting Control for a failed sensor."""

from collections.abc import Sequence

from auvdiag_cli.engine.active import ActiveDiagnosis, DmsRun, decide
from auvdiag_cli.engine.closed_loop import replay_closed_loop
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.detection import look_up
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.results import Diagnosis, Verdict, dms_runs
from auvdiag_cli.engine.segments import ROUTINE_MODE
from auvdiag_cli.engine.signatures import dms_signature
from auvdiag_cli.engine.start_check import StartCheck
from auvdiag_cli.engine.substitution import substitute
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

# The candidate the hypotheses name must leave this many times less of its threshold than
# any other candidate.
DECISIVE_MARGIN = 2.0


def isolate(diagnosis: Diagnosis, b: dict[str, int], alarm_s: float, onset_s: float,
            test: HypothesisTest, companion_runs: Sequence[tuple[DmsRun, int]],
            profile: Profile, model: LoadedModel) -> None:
    """The replay alarmed: read b in the pattern table, then let the DMS runs (this log's
    and its companions'), a weakened thruster's replay or the hypothesis test name the
    component where the table leaves it open or misreads it."""
    apply_detection(diagnosis, b, alarm_s, onset_s, profile, model)
    diagnosis.hypotheses = test
    effort = diagnosis.effort_check
    if effort is not None and effort.suspects:
        diagnosis.notes.append(f"the effort too: {effort.describe()}")
    weak = next((h for h in test.ranked if h.is_actuator), None)
    if len(diagnosis.candidates) > 1:
        own = [(run, diagnosis.start_ns) for run in dms_runs(diagnosis)]
        apply_active_diagnosis(diagnosis, [*own, *companion_runs], profile, model)
    elif diagnosis.substitution is not None:
        if weak is not None and weak.explains:
            apply_weakened_thruster(diagnosis, weak, profile)
    elif not diagnosis.candidates:
        name_by_hypotheses(diagnosis, test, profile, model)


def apply_other_evidence(diagnosis: Diagnosis, check: CommandCheck | None,
                          start: StartCheck, effort: EffortCheck | None, profile: Profile,
                          model: LoadedModel) -> None:
    """The replay raised no alarm: a sensor that read wrong from the start, an actuator
    carrying more of its group's effort than on normal logs, or one driven harder than the
    motion needs, still makes the verdict."""
    if start.off:
        _apply_start_alarm(diagnosis, start, profile, model)
    elif effort is not None and effort.suspects:
        _apply_effort_alarm(diagnosis, effort, check, profile, model)
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


def _apply_effort_alarm(diagnosis: Diagnosis, effort: EffortCheck,
                        check: CommandCheck | None, profile: Profile,
                        model: LoadedModel) -> None:
    """An actuator carries more of its group's effort than on normal logs: the controller
    drives it harder to make up for a weakness near it. Shares that fell are the others
    taking less of the total, not faults of their own."""
    diagnosis.verdict, diagnosis.case = Verdict.FAULT, None
    diagnosis.detected_at_s, diagnosis.onset_s = effort.alarm_s, effort.onset_s
    diagnosis.candidates = list(effort.named)
    note = f"found in the effort the actuators carry: {effort.describe()}"
    if len(effort.named) > 1:
        note += "; more than one actuator is driven harder (a fault near several of them?)"
    if check is not None and check.alarm_s is not None:
        note += f"; the commands against the motion: {check.describe()}"
    diagnosis.notes.append(note)
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


def name_by_hypotheses(diagnosis: Diagnosis, test: HypothesisTest, profile: Profile,
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


def apply_weakened_thruster(diagnosis: Diagnosis, weak: Hypothesis,
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


def apply_active_diagnosis(diagnosis: Diagnosis, runs: list[tuple[DmsRun, int]],
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


def apply_detection(diagnosis: Diagnosis, b: dict[str, int], alarm_s: float, onset_s: float,
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
    histories = diagnosis.histories
    matching = histories.matching
    if sensor is not None and diagnosis.onset_s is not None and matching is not None:
        errors = model.metadata.get("heldout_error", {}).get("rms", {})
        diagnosis.substitution = substitute(
            sensor, histories.sensor_names, histories.time_s, matching.measured,
            matching.modelled, diagnosis.onset_s, profile.navigation, errors.get(sensor.name))
        if profile.controller is not None and diagnosis.mission_legs:
            diagnosis.substitution.closed_loop = replay_closed_loop(
                model, profile.controller, histories.sensor_names, histories.command_names,
                histories.time_s, histories.commands, matching.measured, diagnosis.onset_s,
                diagnosis.mission_legs, profile.dt_s)


