"""Narrowing the pattern table's candidates down to one: the DMS runs (active diagnosis),
what the model predicts each candidate's failure shows on them, the hypothesis test, and
the effort each candidate carries in its group."""

from collections.abc import Sequence
from dataclasses import replace

from auvdiag_cli.engine.active import ActiveDiagnosis, DmsRun, decide
from auvdiag_cli.engine.frozen_sensor import FROZEN_WHY, frozen_in
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.results import Finding, Observations
from auvdiag_cli.engine.signatures import dms_signature
from auvdiag_cli.vehicle.profile import Sensor

# The candidate the hypotheses name must leave this many times less of its threshold than
# any other candidate.
DECISIVE_MARGIN = 2.0
# Two hypotheses whose g peaks lie within this ratio of each other are a tie: the replay's
# noise moves a peak that much between seeds of one mission (a weak vertical thruster of a
# BlueROV2 against the other one, 1.00-1.07x; the wrong one ranked first in about half).
TIED_MARGIN = 1.1


def narrowed(seen: Observations, finding: Finding, runs: Sequence[tuple[DmsRun, int]],
             judging: Judging) -> Finding:
    """``finding`` with the candidates the evidence leaves (`Finding.active` says how)."""
    assert finding.onset_s is not None
    onset_ns = seen.start_ns + round(finding.onset_s * 1e9)
    active = decide(finding.candidates, onset_ns, runs, judging.profile)
    if active.conflict:
        finding = finding.noted("the DMS runs contradict each other (more than one fault?); "
                                "all candidates kept")
    if len(active.candidates) > 1:
        active, finding = _narrow_by_frozen(seen, finding, active, judging)
    if len(active.candidates) > 1:
        active, finding = _narrow_by_predicted_signatures(finding, active, onset_ns, runs,
                                                          judging)
    if len(active.candidates) > 1 and finding.hypotheses is not None:
        active, finding = _narrow_by_hypotheses(seen, finding, active, finding.hypotheses)
    if len(active.candidates) > 1:
        active, finding = _narrow_by_effort(seen, finding, active)
    return replace(finding, active=active, candidates=active.candidates)


def weak_alone(seen: Observations, time_s: float | None, until_s: float | None = None
               ) -> str | None:
    """The actuator whose group's shares match its weakness alone, begun by ``time_s`` (or
    by a moment from it to ``until_s``: `EffortCheck.alone_by`), or None."""
    effort = seen.effort_check
    return None if effort is None else effort.alone_by(time_s, until_s)


def weak_throughout(seen: Observations) -> str | None:
    """The actuator whose group's shares match its weakness alone over the whole log, with
    no change within it (`EffortCheck.throughout`), or None."""
    effort = seen.effort_check
    return None if effort is None else effort.throughout()


def group_mate_instead(seen: Observations, finding: Finding, component: str) -> str | None:
    """Another member of ``component``'s effort group, where its group's shares match that
    member weak alone, begun by the detection (`weak_alone`); else None. The shares measure
    which member the controller drives harder; a replay tells a group's members apart only
    as far as its normal logs moved them apart, and a failed member's command pushed past
    anything they held is beyond what it learned (a simulated quadrotor's rotor stopped 3 s
    before the log's end: its replay explained the log by the diagonal partner stopped)."""
    alone = weak_alone(seen, finding.onset_s, finding.detected_at_s)
    effort = seen.effort_check
    if alone is None or alone == component or effort is None:
        return None
    group = {a.component: a.group for a in effort.actuators}
    return alone if group.get(component) is not None and group.get(component) == group.get(
        alone) else None


def unsupported_table(seen: Observations, finding: Finding, test: HypothesisTest,
                      sensors: Sequence[Sensor]) -> str | None:
    """The actuator to name instead of the sensor the pattern table reads, or None: where
    none of that sensor's faults explains the log, the hypothesis of one actuator comes
    closer than any of them, and its group's shares match that actuator weak alone, seen
    from the replay's onset to its detection (a thruster dying as the vehicle dives raises
    the depth-rate sensor's row), or the commands against the motion name it alone while
    resting on none of that sensor's signals (``sensors``: the profile's). A sensor's fault
    in a closed loop moves the shares too (the controller answers what it misreads), but
    then its own replay comes closest."""
    sensor = closest(test, finding.component)
    if sensor < 1.0:
        return None
    effort = seen.effort_check
    alone = None if effort is None else effort.alone_by(finding.onset_s,
                                                        finding.detected_at_s)
    check = seen.command_check
    if alone is None and check is not None and check.rests_on is not None and not any(
            s.name in check.rests_on for s in sensors if s.component == finding.component):
        alone = commands_alone(seen, finding)
    return alone if alone is not None and closest(test, alone) < sensor else None


def tied_with(test: HypothesisTest, chosen: Hypothesis) -> Hypothesis | None:
    """The best hypothesis of another component that explains the log about as well as
    ``chosen`` (its g peak within TIED_MARGIN of ``chosen``'s), or None: neither can be
    named over the other from the replay alone. A bias or a drift fitted to the log after
    the onset absorbs what a weak actuator did to a signal, and is no rival."""
    rival = next((h for h in test.ranked
                  if h.component != chosen.component and not h.fitted), None)
    if rival is None or not rival.explains:
        return None
    return rival if rival.peak_g_ratio < TIED_MARGIN * max(chosen.peak_g_ratio, 1e-9) else None


def commands_alone(seen: Observations, finding: Finding) -> str | None:
    """The one actuator the commands against the motion name (the motion short of its
    thrust, or the command beyond what the motion needs), their windows over begun by the
    replay's detection: the same event, measured on that actuator alone; else None."""
    check = seen.command_check
    if check is None or check.alarm_s is None or len(check.named) != 1:
        return None
    began = check.earliest_s
    return check.named[0] if (began is not None and finding.detected_at_s is not None
                              and began <= finding.detected_at_s) else None


def closest(test: HypothesisTest, component: str | None,
             kinds: tuple[str, ...] | None = None) -> float:
    """The largest g / threshold the best of ``component``'s hypotheses (of ``kinds``: all)
    leaves."""
    return min((h.peak_g_ratio for h in test.ranked if h.component == component
                and (kinds is None or h.kind in kinds)), default=float("inf"))


def _narrow_by_frozen(seen: Observations, finding: Finding, active: ActiveDiagnosis,
                      judging: Judging) -> tuple[ActiveDiagnosis, Finding]:
    """Among the candidates left, the sensor whose every reading froze at one value from
    the onset on (`frozen_sensor`): what no motion and no other part's fault gives."""
    frozen = frozen_in(seen, finding.onset_s, judging)
    if frozen is None or frozen not in active.candidates:
        return active, finding
    finding = finding.noted(f"the pattern table reads b as {' or '.join(active.candidates)}; "
                            f"{frozen} is {FROZEN_WHY}")
    return replace(active, candidates=(frozen,), recommended_dms=()), finding


def _narrow_by_effort(seen: Observations, finding: Finding, active: ActiveDiagnosis
                      ) -> tuple[ActiveDiagnosis, Finding]:
    """Among the candidates left, the actuator whose group's shares match its weakness
    alone, begun by the detection (`EffortCheck.alone_by`: the same event) or over the
    whole log (`weak_throughout`): the controller drives the weak one harder, which tells
    apart actuators that move the vehicle alike (a vectored ROV's two vertical thrusters);
    unless a sensor among them, dead or stuck, explains the log better."""
    begun = weak_alone(seen, finding.onset_s, finding.detected_at_s)
    alone = begun or weak_throughout(seen)
    if alone is None or alone not in active.candidates:
        return active, finding
    test = finding.hypotheses
    if test is not None and any(
            closest(test, c, ("dead", "stuck")) < min(1.0, closest(test, alone))
            for c in active.candidates
            if any(h.component == c and not h.is_actuator for h in test.ranked)):
        # A sensor's fault in a closed loop moves the shares too (the controller answers what
        # it misreads, a dead gyro spinning the vehicle): its replay dead or stuck then
        # explains the log, and comes closer. A fitted bias or drift absorbs a weak
        # thruster's effect on one signal, and does not count.
        return active, finding
    finding = finding.noted(
        f"the pattern table reads b as {' or '.join(active.candidates)}; the effort their "
        f"group carries tells them apart: its shares match {alone} weak alone, "
        + ("begun by the detection" if begun else "over the whole log"))
    return replace(active, candidates=(alone,), recommended_dms=()), finding


def _narrow_by_hypotheses(seen: Observations, finding: Finding, active: ActiveDiagnosis,
                          test: HypothesisTest) -> tuple[ActiveDiagnosis, Finding]:
    """Among the candidates the DMS runs leave, the one whose failure explains the log when
    no other candidate's does, by DECISIVE_MARGIN at least (e.g. which thruster died on a
    plain mission: the table reads both the same); not where the effort its group carries
    names another member of the group alone (`group_mate_instead`: the effort decides)."""
    best = {c: min((h for h in test.ranked if h.component == c),
                   key=lambda h: h.peak_g_ratio, default=None) for c in active.candidates}
    scored = sorted((h for h in best.values() if h is not None), key=lambda h: h.peak_g_ratio)
    if len(scored) < 2 or not scored[0].explains or scored[1].explains:
        return active, finding
    margin = scored[1].peak_g_ratio / max(scored[0].peak_g_ratio, 1e-9)
    if margin < DECISIVE_MARGIN:
        return active, finding
    winner = scored[0]
    if winner.is_actuator and group_mate_instead(seen, finding, winner.component) is not None:
        return active, finding
    finding = finding.noted(
        f"the pattern table reads b as {' or '.join(active.candidates)}; replayed from the "
        f"onset, {winner.describe()} explains the log (g at most {winner.peak_g_ratio:.0%} of "
        f"its threshold) and {scored[1].describe()} does not ({scored[1].peak_g_ratio:.0%})")
    if winner.kind == "weakened":
        finding = replace(finding, degradation=winner)
    return replace(active, candidates=(winner.component,), recommended_dms=()), finding


def _narrow_by_predicted_signatures(finding: Finding, active: ActiveDiagnosis,
                                    onset_ns: int, runs: Sequence[tuple[DmsRun, int]],
                                    judging: Judging
                                    ) -> tuple[ActiveDiagnosis, Finding]:
    """Where moving or not moving a component cannot separate the candidates (a thruster
    and the sensor of the motion it drives), the model can: it predicts each candidate's b
    on every DMS run made wholly with the fault present. A run that stayed quiet (b = 0)
    clears the candidates whose failure would have shown on it; a run that raised an alarm
    clears those whose failure would not have. Which bits an alarm raises is left out: near
    a threshold the model cannot call single bits reliably. Never all are cleared."""
    kept = list(active.candidates)
    for run, _ in runs:
        if run.start_ns < onset_ns or run.name not in judging.profile.dms:
            continue
        alarm = any(run.b.values())
        predicted = {c: any(dms_signature(judging.model, judging.profile, run.name,
                                          c).values()) for c in kept}
        agreeing = [c for c in kept if predicted[c] == alarm]
        if agreeing and len(agreeing) < len(kept):
            seen = "".join(str(v) for v in run.b.values())
            dropped = [c for c in kept if c not in agreeing]
            would = "would have shown on it" if not alarm else "would not have shown on it"
            finding = finding.noted(f"{run.name} in {run.log} gave b = {seen}: the model says "
                                    f"a failed {' or '.join(dropped)} {would}")
            kept = agreeing
    # The DMSs on which the remaining candidates' failures look different decide next time.
    recommended = () if len(kept) == 1 else tuple(
        name for name in judging.profile.dms
        if len({tuple(dms_signature(judging.model, judging.profile, name, c).values())
                for c in kept}) > 1)
    return replace(active, candidates=tuple(kept), recommended_dms=recommended), finding


