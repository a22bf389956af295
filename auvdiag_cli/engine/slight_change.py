"""A change-test alarm too slight for thresholds few logs set.

`calibrate` sets the change test's thresholds from each normal log's largest statistics
(the calibration logs' and those of the logs the model was trained on); with fewer than
SETTLED_LOGS of them the margin rule sets them, and the largest of so few is often passed
by the next normal log. A simulated quadrotor trained and calibrated on four normal logs:
2 of 30 normal missions of other noise seeds ended "FAULT: barometer", the change test
alone having crossed its climb threshold by 7 %, every other judge quiet. A fault the
change test alone raised, whose statistics stayed under SLIGHT times those thresholds all
log long, is undetermined, saying how far they went and what would judge it. With
SETTLED_LOGS logs or more, or a crossing past SLIGHT, or another judge's alarm, it stands."""

from dataclasses import replace

import numpy as np

from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.settled import SETTLED_LOGS, SLIGHT, judged_ratios

TOO_SLIGHT_CHANGE = "a change too slight for thresholds set on few logs"


def beyond_slight_change(finding: Finding, normal: Finding, seen: Observations,
                         change_logs: int | None) -> Finding:
    """``finding``, or undetermined (``normal``'s notes) where it is a fault of the change
    test alone, crossed by less than SLIGHT, on thresholds that rest on ``change_logs``
    normal logs, fewer than SETTLED_LOGS (None: not known, as a model from before)."""
    change = seen.change_check
    if (finding.verdict is not Verdict.FAULT or change is None or change.alarm_s is None
            or change_logs is None or change_logs >= SETTLED_LOGS
            or not _change_alone(seen)):
        return finding
    ratios = change.peak_ratios()
    furthest = max(ratios, key=lambda name: ratios[name], default=None)
    if furthest is None or ratios[furthest] >= SLIGHT:
        return finding
    named = finding.component or " or ".join(finding.candidates) or "no single component"
    return replace(normal, verdict=Verdict.UNDETERMINED, case=None,
                   undetermined_because=TOO_SLIGHT_CHANGE).noted(
        f"a change at {change.alarm_s:.1f} s (it named {named}) is not taken for a fault: "
        f"the change test's {furthest} reached {ratios[furthest]:.2f} x its threshold at "
        f"most, no other judge saw anything, and its thresholds rest on {change_logs} normal "
        f"log(s), which a normal log may pass this far; calibrate on {SETTLED_LOGS} or more "
        "normal logs (those the model was trained on count) to judge it")


def _change_alone(seen: Observations) -> bool:
    """Whether the change test alarmed and no other judge did: the replay's judged g never
    crossed its thresholds, and the commands, the effort shares and the start stayed
    quiet."""
    command, effort, start = seen.command_check, seen.effort_check, seen.start_check
    ratios = judged_ratios(seen)
    replay_quiet = ratios is None or not np.any(np.nan_to_num(ratios) >= 1.0)
    return (replay_quiet and (command is None or command.alarm_s is None)
            and (effort is None or effort.alarm_s is None)
            and (start is None or not start.off))
