"""A log the effort shares neither clear nor convict: nothing alarmed, but one actuator's
share is past the threshold a looser false-alarm budget would set, on the few normal logs
the model rests on, and its group's departure matches that actuator's weakness clearly
(`effort_naming.not_ruled_out`). With four normal logs a 1 %-a-log threshold is wide, and
a propeller cut enough to load its rotor 10 % more falls under it about one log in four
(a simulated quadrotor); "normal" there would claim more than the logs know."""

from dataclasses import replace

from auvdiag_cli.engine.results import Finding, Observations, Verdict


def not_ruled_out_because(component: str) -> str:
    """Why the verdict is undetermined, the component named (the JSON's
    `undetermined_because`)."""
    return (f"{component} may be weak: it carries more of the effort than normal, short of "
            "its threshold, and the few normal logs the model rests on cannot rule that out")


def unless_not_ruled_out(finding: Finding, seen: Observations) -> Finding:
    """``finding``, or where it is normal and the effort shares cannot rule out one weak
    actuator, undetermined with that actuator's component as the candidate."""
    effort = seen.effort_check
    if finding.verdict is not Verdict.NORMAL or effort is None or effort.not_ruled_out is None:
        return finding
    return replace(finding, verdict=Verdict.UNDETERMINED, case=None,
                   candidates=(effort.not_ruled_out,),
                   undetermined_because=not_ruled_out_because(effort.not_ruled_out)).noted(
        "not judged normal: the effort shares cannot rule out a weak "
        f"{effort.not_ruled_out} (the effort shares' summary says why); calibrate the model "
        f"on more normal logs (auvdiag calibrate) to judge it{_in_all(effort.judged_with_logs)}")


def _in_all(logs: int | None) -> str:
    return "" if logs is None else f" (about {logs} in all, like these, would)"
