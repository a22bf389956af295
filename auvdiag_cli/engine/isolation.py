"""Naming the component once the replay alarmed (the pattern table, the hypothesis test,
the DMS runs of `narrowing`, a weakened thruster); each step maps the finding so far to the
next. Alarms of the other judges are named in `other_alarms`, the component and its
Substituting Control in `naming`."""

from collections.abc import Mapping, Sequence
from dataclasses import replace

from auvdiag_cli.engine.active import DmsRun
from auvdiag_cli.engine.detection import look_up
from auvdiag_cli.engine.frozen_sensor import FROZEN_WHY, frozen_in
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.naming import found, name_component
from auvdiag_cli.engine.narrowing import (
    DECISIVE_MARGIN,
    closest,
    commands_alone,
    group_mate_instead,
    narrowed,
    tied_with,
    unsupported_table,
    weak_alone,
    weak_throughout,
)
from auvdiag_cli.engine.results import Finding, Observations, Verdict, dms_runs
from auvdiag_cli.engine.segments import ROUTINE_MODE
from auvdiag_cli.engine.signatures import dms_signature
from auvdiag_cli.engine.weakened_naming import left_undecided, name_weakened


def isolate(seen: Observations, finding: Finding, b: Mapping[str, int], alarm_s: float,
            onset_s: float, test: HypothesisTest,
            companion_runs: Sequence[tuple[DmsRun, int]], judging: Judging) -> Finding:
    """The replay alarmed: read b in the pattern table, then let the DMS runs (this log's
    and its companions'), a weakened thruster's replay or the hypothesis test name the
    component where the table leaves it open or misreads it."""
    finding = replace(apply_detection(seen, finding, b, alarm_s, onset_s, judging),
                      hypotheses=test)
    if (effort := seen.effort_check) is not None and effort.suspects:
        finding = finding.noted(f"the effort too: {effort.describe()}")
    weak = next((h for h in test.ranked if h.is_actuator), None)
    if len(finding.candidates) > 1:
        own = [(run, seen.start_ns) for run in dms_runs(seen)]
        return apply_active_diagnosis(seen, finding, [*own, *companion_runs], judging)
    if finding.substitution is not None:
        if weak is not None and weak.explains and _outweighs_the_table(weak, finding, test):
            measured = _measured_instead(seen, finding, test)
            if measured is not None:
                return measured
            return name_weakened(seen, finding, weak, test, judging.profile)
        alone = unsupported_table(seen, finding, test, judging.profile.sensors)
        if alone is not None:
            return _instead_of_the_table(finding, alone, test, seen)
        return finding
    if not finding.candidates:
        return name_by_hypotheses(seen, finding, test, judging)
    return finding


def _instead_of_the_table(finding: Finding, actuator: str, test: HypothesisTest,
                          seen: Observations) -> Finding:
    """``actuator`` named where the table read a sensor that no fault of its own explains
    (`narrowing.unsupported_table`)."""
    table_says = finding.component
    best = min((h for h in test.ranked if h.component == actuator),
               key=lambda h: h.peak_g_ratio)
    effort = seen.effort_check
    measured = (f"the effort its group carries matches {actuator} weak alone, seen then"
                if effort is not None and effort.alone_by(finding.onset_s,
                                                          finding.detected_at_s) == actuator
                else "the commands against the motion name it alone: "
                + (seen.command_check.describe() if seen.command_check else ""))
    return replace(finding, component=actuator, candidates=(actuator,),
                   substitution=None).noted(
        f"the pattern table reads b as {table_says}, but no fault of it explains the log (the "
        f"closest leaves g at {closest(test, table_says):.0%} of its threshold); "
        f"{best.describe()} comes closer ({best.peak_g_ratio:.0%}), and {measured}: "
        f"{actuator} is named")


def _measured_instead(seen: Observations, finding: Finding, test: HypothesisTest
                      ) -> Finding | None:
    """Where the hypotheses that explain the log are of actuators and do not decide between
    them (the best by less than DECISIVE_MARGIN), the one actuator the commands against
    the motion measured short (`narrowing.commands_alone`) is named: its own evidence,
    where the replay's g is reached about as well by several; else None."""
    best, margin, check = test.best, test.margin, seen.command_check
    named = commands_alone(seen, finding)
    if (named is None or check is None or not best.is_actuator or named == best.component
            or margin is None or margin >= DECISIVE_MARGIN
            or not any(h.component == named for h in test.ranked)):
        return None
    return replace(finding, component=named, candidates=(named,), substitution=None,
                   degradation=None).noted(
        f"the pattern table reads b as {finding.component}; the hypothesis test does not "
        f"decide (best {best.describe()}, {margin:.1f}x the next); the commands against the "
        f"motion name {named} alone: {check.describe()}")


def _outweighs_the_table(weak: Hypothesis, finding: Finding, test: HypothesisTest) -> bool:
    """Whether a weak actuator's replay explains the log decisively better than the sensor
    the table names, dead or stuck: where both explain it about as well (a dead DVL against
    a thruster whose weakness moves the same signal), the table's reading stands. A bias or
    a drift is fitted to the log, and absorbs a weak thruster's effect on one signal."""
    sensor = min((h.peak_g_ratio for h in test.ranked if h.component == finding.component
                  and h.kind in ("dead", "stuck")), default=float("inf"))
    return sensor >= 1.0 or weak.peak_g_ratio * DECISIVE_MARGIN <= sensor


def name_by_hypotheses(seen: Observations, finding: Finding, test: HypothesisTest,
                       judging: Judging) -> Finding:
    """No row of the pattern table names the component (or there is no table): the
    hypothesis that explains the log does, when one does; when none does (a vehicle that
    lost control), or a sensor's does only on the signals the replay judges while the change
    showed in others, the actuator whose effort shares match its weakness alone, begun then
    (or there over the whole log: there when the motion departed)."""
    best, runner_up, margin = test.best, test.runner_up, test.margin
    effort = seen.effort_check
    # The same event where the effort's change began by the replay's detection: an onset
    # dated from a window's residual may come before the change the shares date closely.
    alone = weak_alone(seen, finding.onset_s, finding.detected_at_s)
    if not best.explains:
        raised = ", ".join(k for k, v in finding.b.items() if v)
        note = (f"anomaly on {raised}: no single-component fault explains it (the closest, "
                f"{best.describe()}, leaves g at {best.peak_g_ratio:.0%} of its threshold)")
        if (frozen := frozen_in(seen, finding.onset_s, judging)) is not None:
            return found(seen, finding, [frozen], f"{note}; named as {FROZEN_WHY}", judging)
        if (weak := alone or weak_throughout(seen)) is None:
            return finding.noted(note)
        whole = "" if alone else ", over the whole log"
        return found(seen, finding, [weak], f"{note}; named by the effort its group carries"
                      f" (its shares match {weak} weak alone{whole})", judging)
    beside = ("" if runner_up is None or margin is None else
              f"; runner-up {runner_up.describe()} ({runner_up.peak_g_ratio:.0%}, "
              f"{margin:.1f}x the best)")
    why = _shares_overrule(seen, finding, best, alone)
    if alone is not None and why is not None:
        return found(seen, finding, [alone],
                      f"named by the effort its group carries (its shares match {alone} weak "
                      f"alone, begun by the detection): the hypothesis test favours "
                      f"{best.describe()} but {why}", judging)
    if (effort is not None and len(effort.named) == 1 and margin is not None
            and margin < DECISIVE_MARGIN):
        # The motion departed, but several single faults explain it about as well; the
        # actuator its group's effort points at is the specific evidence.
        return found(seen, finding, list(effort.named),
                      f"named by the effort its group carries ({effort.named[0]}, above): "
                      f"the hypothesis test does not decide (best {best.describe()}"
                      f"{beside})",
                      judging)
    rival = tied_with(test, best)
    if rival is not None:
        return left_undecided(finding, best, rival)
    if best.kind == "weakened":
        finding = replace(finding, degradation=best)
    return found(seen, finding, [best.component],
                  f"named by the hypothesis test: {best.describe()} explains the log (g then "
                  f"stays at {best.peak_g_ratio:.0%} of its threshold at most){beside}",
                  judging)


def _shares_overrule(seen: Observations, finding: Finding, best: Hypothesis,
                     alone: str | None) -> str | None:
    """Why the actuator whose group's shares match its weakness alone (``alone``, begun by
    the onset) is named over the hypothesis test's ``best``, or None."""
    if alone is None:
        return None
    if best.is_actuator:
        return None if group_mate_instead(seen, finding, best.component) is None else (
            f"it is another member of that group (g at {best.peak_g_ratio:.0%} of its "
            "threshold): which member the controller drives harder is what the shares measure")
    effort = seen.effort_check
    unweighed = [n for n, v in finding.b.items() if v and n in seen.not_judged]
    # The hypotheses are weighed by the replay's g, which leaves out signals it cannot
    # predict: a sensor's fault "explains" a change there only by not being looked at.
    if unweighed:
        return (f"cannot weigh {', '.join(unweighed)} (not judged by the replay), where the "
                "change showed")
    # A bias or a drift fitted to the log after the onset absorbs what a weak actuator did
    # to the signal (a rotor that died seconds before the log ends), while a sensor's fault
    # moves a group of three or more in pairs, never as one member's weakness alone (a
    # pair's shares move as one member's whatever moved them).
    if best.fitted and effort is not None and len(effort.matches) > 2:
        return ("fits it to the log after the onset, where it absorbs what a weak actuator "
                "does to the signal")
    return None


def apply_active_diagnosis(seen: Observations, finding: Finding,
                           runs: Sequence[tuple[DmsRun, int]], judging: Judging) -> Finding:
    finding = narrowed(seen, finding, runs, judging)
    if len(finding.candidates) == 1:
        return name_component(seen, finding, finding.candidates[0], judging)
    return finding


def apply_detection(seen: Observations, finding: Finding, b: Mapping[str, int],
                    alarm_s: float, onset_s: float, judging: Judging) -> Finding:
    row = look_up(judging.profile.pattern, dict(b))
    finding = replace(finding, verdict=Verdict.FAULT, b=dict(b),
                      detected_at_s=round(float(alarm_s), 3), onset_s=round(float(onset_s), 3),
                      case=None if row is None else row.case)
    if row is not None:
        candidates = list(row.components)
    else:
        candidates, finding = _predicted_on_dms(seen, finding, b, alarm_s, judging)
    # A profile without a table naming parts (none, or only its "nothing" row) is not
    # reminded of it on every log: the other evidence names the part there.
    if not candidates and any(r.components for r in judging.profile.pattern):
        finding = finding.noted(f"b = {dict(b)} fits no row of the pattern table: more than "
                                "one fault, or one the table does not describe")
    finding = replace(finding, candidates=tuple(candidates))
    if len(candidates) == 1:
        return name_component(seen, finding, candidates[0], judging)
    return finding


def _predicted_on_dms(seen: Observations, finding: Finding, b: Mapping[str, int],
                      alarm_s: float, judging: Judging
                      ) -> tuple[list[str], Finding]:
    """The table describes the mission; a DMS moves the vehicle otherwise, so a failure can
    show there with a b of its own. When the alarm came on a DMS, the candidates are the
    components whose failure, the model predicts, raises one of the same bits on it (the
    DMS runs that follow narrow them down)."""
    segment = next((r.segment for r in seen.segments
                    if r.segment.mode == ROUTINE_MODE and r.segment.name in judging.profile.dms
                    and r.segment.start_s <= alarm_s <= r.segment.end_s), None)
    if segment is None:
        return [], finding
    components = [c.component for c in judging.profile.commands] + [s.component
                                                            for s in judging.profile.sensors]
    matching = [c for c in components
                if any(b[k] and v for k, v in
                       dms_signature(judging.model, judging.profile, segment.name, c).items())]
    if matching:
        bits = "".join(str(v) for v in b.values())
        finding = finding.noted(f"b = {bits} on {segment.name} fits no row of the pattern "
                                "table (which describes the mission); the model predicts an "
                                f"alarm on one of these signals on {segment.name} for: "
                                f"{', '.join(matching)}")
    return matching, finding

