"""The verdict where a judge beside the replay found the fault: the log against its own
beginning (the change test), a sensor that read wrong from the start, an actuator carrying
more of its group's effort than on normal logs, or one driven harder than the motion
needs."""

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.change_suspects import carriers, change_suspects
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.detection import look_up
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.failure_effect import failure_effect, healthy_from_onset
from auvdiag_cli.engine.frozen_sensor import FROZEN_WHY, frozen_in
from auvdiag_cli.engine.judging import Judging, unpredicted
from auvdiag_cli.engine.naming import found
from auvdiag_cli.engine.narrowing import weak_alone
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.start_check import StartCheck


def apply_other_evidence(seen: Observations, finding: Finding, judging: Judging) -> Finding:
    """The replay raised no alarm: a sensor that read wrong from the start, an actuator
    carrying more of its group's effort than on normal logs, or one driven harder than the
    motion needs, still makes the verdict."""
    check, start, effort = seen.command_check, seen.start_check, seen.effort_check
    if start is not None and start.off:
        return _apply_start_alarm(seen, finding, start, judging)
    if effort is not None and effort.suspects:
        return _apply_effort_alarm(seen, finding, effort, check, judging)
    if check is not None and check.alarm_s is not None:
        return _apply_command_alarm(seen, finding, check, judging)
    return finding


def apply_change_alarm(seen: Observations, finding: Finding, change: ChangeCheck,
                       judging: Judging, healthy: np.ndarray | None = None) -> Finding:
    """The log changed against its own beginning before the replay's thresholds were
    crossed, in signals the profile says which parts move: the signals that changed make
    b; a row of the pattern table names the part, else the part that moves most of what
    changed (`change_suspects`). ``healthy``: the model of the healthy vehicle replayed
    from the measured state at the onset, which gives the failure's effect (none: the
    effect is not said)."""
    b = {name: int(name in change.changed) for name in finding.b}
    finding = replace(finding, verdict=Verdict.FAULT, b=b, detected_at_s=change.alarm_s,
                      onset_s=change.onset_s)
    note = f"found by the change test: {change.describe()}"
    # The effort's shares matching one actuator weak alone, begun by the change's alarm:
    # the same event, measured on that actuator.
    alone = weak_alone(seen, change.onset_s, change.alarm_s)
    row = look_up(judging.profile.pattern, b)
    if row is not None and row.components:
        return _by_row(seen, replace(finding, case=row.case), row.components, alone, note,
                       judging)
    if (frozen := frozen_in(seen, change.onset_s, judging)) is not None:
        return found(seen, replace(finding, case=None), [frozen], f"{note}; named as "
                      f"{FROZEN_WHY}", judging)
    ranked = change_suspects(change.flagged, judging.profile, change.evidence,
                              change.ways)
    if alone is not None and (not ranked or ranked[0] in {s.component
                                                          for s in judging.profile.sensors}):
        # A weak actuator moves what a sensor measures too, and a lost one moves every
        # signal at once (no part's signature fits): its group's shares say which.
        instead = (f"not {ranked[0]}, whose signals changed" if ranked
                   else "where no one part moves what changed")
        first, when = _effort_first(seen, replace(finding, case=None))
        return found(seen, first, [alone], f"{note}; named by the effort its group carries "
                      f"(its shares match {alone} weak alone, begun by the change's alarm), "
                      f"{instead}{when}", judging)
    named = ranked[:1]
    if change.since_judged and len(ranked) > 1:
        # What the failure moved first lies in the reference; what changes after it is
        # often the vehicle's answer (an engine lost 10 s before judging began left the
        # roll as the signal that changed most, and "ailerons" named).
        named = ranked[:2]
        note += (f"; no one part is named: the change may have begun before the first step "
                 f"judged ({change.judged_from_s:.1f} s), in the log's own beginning the test "
                 "takes as its reference, where what the failure moved first is not seen, and "
                 f"what changed after it{carriers(change)} may be the vehicle's answer; the "
                 f"likeliest parts: {' or '.join(named)}")
    elif len(ranked) > 1:
        note += (f"; the part that moves most of what changed{carriers(change)} is named, "
                 "before " + ", ".join(ranked[1:]))
    if healthy is not None:
        horizon, cannot = judging.model.horizon_steps, unpredicted(judging.model)
        effect = failure_effect(seen, change, healthy, horizon, cannot)
        note += "; " + effect if effect else ""
        finding = replace(finding, healthy_from_onset=healthy_from_onset(
            seen, change, healthy, horizon, cannot))
    return found(seen, replace(finding, case=None), named, note, judging)


def _by_row(seen: Observations, finding: Finding, components: Sequence[str],
            alone: str | None, note: str, judging: Judging) -> Finding:
    """The change test's b read in the pattern table: its row's ``components``, or where
    they are parts that move the vehicle alike (a ROV's two vertical thrusters), the one
    whose group's shares match it weak alone, begun by the change's alarm (``alone``): the
    controller drives the weak one harder from then."""
    if alone is None or len(components) < 2 or alone not in components:
        return found(seen, finding, list(components), note, judging)
    first, when = _effort_first(seen, finding)
    return found(seen, first, [alone], f"{note}; the pattern table reads b as "
                  f"{' or '.join(components)}; the effort their group carries tells them "
                  f"apart: its shares match {alone} weak alone, begun by the change's "
                  f"alarm{when}", judging)


def _effort_first(seen: Observations, finding: Finding) -> tuple[Finding, str]:
    """``finding`` with the effort's detection where its shares saw the event before the
    change test (a stopped thruster's shares move at once, while the motion it leaves, the
    controller answering it, builds up over seconds), and its onset where they date it
    earlier (a weak vertical thruster's shares rose from its onset, the roll rate departed
    12 s later); and what the note adds."""
    effort = seen.effort_check
    if effort is None or effort.alarm_s is None or effort.onset_s is None \
            or finding.detected_at_s is None or finding.onset_s is None:
        return finding, ""
    seen_first = effort.alarm_s < finding.detected_at_s
    dated_first = effort.onset_s < finding.onset_s
    if not seen_first and not dated_first:
        return finding, ""
    said = ([f"saw it first, at {effort.alarm_s:.1f} s"] if seen_first else []) + (
        [f"date it from ~{effort.onset_s:.1f} s"] if dated_first else [])
    return (replace(finding, detected_at_s=min(effort.alarm_s, finding.detected_at_s),
                    onset_s=min(effort.onset_s, finding.onset_s)),
            f"; the shares {' and '.join(said)}: the verdict's times")


def _apply_start_alarm(seen: Observations, finding: Finding, start: StartCheck,
                       judging: Judging) -> Finding:
    """The replay starts from the measured state and takes a wrong start reading as the
    truth; the sensors that started away from where normal logs start are the candidates."""
    finding = replace(finding, verdict=Verdict.FAULT, case=None, onset_s=0.0,
                      detected_at_s=start.at_s)
    candidates = list(dict.fromkeys(s.component for s in judging.profile.sensors
                                    if s.name in start.off))
    return found(seen, finding, candidates, "found at the start of the log: "
                  + start.describe(seen.sensor_units), judging)


def _apply_effort_alarm(seen: Observations, finding: Finding, effort: EffortCheck,
                        check: CommandCheck | None, judging: Judging) -> Finding:
    """An actuator carries more of its group's effort than on normal logs: the controller
    drives it harder to make up for a weakness near it. Shares that fell are the others
    taking less of the total, not faults of their own."""
    note = f"found in the effort the actuators carry: {effort.describe()}{effort.several()}"
    named, (detected, onset) = effort.named, (effort.alarm_s, effort.onset_s)
    if check is not None and check.alarm_s is not None:
        named = effort.told_by(check.named)
        detected, onset = effort.seen_with(check.named, check.alarm_s, check.onset_s)
        note += f"; the commands against the motion: {check.describe()}" + (
            f", which tells {named[0]} from the others" if named != effort.named else "")
    return found(seen, replace(finding, verdict=Verdict.FAULT, case=None,
                                detected_at_s=detected, onset_s=onset), list(named), note, judging)


def _apply_command_alarm(seen: Observations, finding: Finding, check: CommandCheck,
                         judging: Judging) -> Finding:
    """The motion looks normal (or cannot be judged) but an actuator works harder than the
    motion needs: a weakened actuator whose loss the controller makes up for."""
    finding = replace(finding, verdict=Verdict.FAULT, case=None,
                      detected_at_s=check.alarm_s, onset_s=check.onset_s)
    # A sensor reading the motion wrongly also makes the controller push harder; the motion
    # model rules that out only for the sensors it judges.
    unjudged = [s.component for s in judging.profile.sensors if s.name in seen.not_judged
                and (check.rests_on is None or s.name in check.rests_on)]
    candidates = list(dict.fromkeys([*check.named, *unjudged])) if check.named else []
    note = f"found in the commands, not the motion: {check.describe()}"
    if len(check.named) > 1:
        note += "; these actuators act alike on the vehicle and cannot be told apart from it"
    if check.named and unjudged:
        note += ("; a misreading " + " or ".join(dict.fromkeys(unjudged)) + " (not judged by "
                 "the motion model) would look the same")
    return found(seen, finding, candidates, note, judging)
