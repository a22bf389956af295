"""A change-test alarm too slight for thresholds few normal logs set: the log changed against
its own beginning by a little more than the largest change those logs showed (times the
margin, or the test's floor), and no other judge saw anything.

How far a log departs from its own beginning depends on what it was asked to do after it: a
turn into a current the reference never met, a leg flown faster. With three normal logs
behind the thresholds, their largest value is about the normal logs' 75th percentile, and
the next normal log passes the margin often: a simulated BlueROV2 trained and calibrated on
three missions raised the change test on 4 of 20 normal missions of other noise seeds (sway
1.03-1.22 x its threshold, roll rate 1.37 x), each crossing for 0.3-3 s. The ALFA aircraft
modelled from one day's three normal flights crossed its thresholds on three failed flights
of other days by the same little (1.05-1.24 x, for 0.2-3 s), every other judge quiet.
Nothing in such an alarm tells a failure from the next normal log: the verdict is
undetermined, saying how far the test went and what would judge it. An alarm any other
judge bears out (the replay, the commands against the motion, the effort shares, the
start), and any over SLIGHT times its threshold, stands."""

from dataclasses import replace

import numpy as np

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.settled import SETTLED_LOGS, SLIGHT, judged_ratios
from models.card import ModelCard

FEW_CHANGE_LOGS = "change-test thresholds set on few normal logs"


def beyond_slight_change(finding: Finding, normal: Finding, seen: Observations,
                         card: ModelCard) -> Finding:
    """``finding``, or undetermined where it is the change test's alarm alone, over
    thresholds set on fewer than SETTLED_LOGS normal logs by less than SLIGHT times them
    from the alarm on."""
    change = seen.change_check
    if (finding.verdict is not Verdict.FAULT or change is None or change.alarm_s is None
            or finding.detected_at_s != change.alarm_s or card.change_logs is None
            or card.change_logs >= SETTLED_LOGS or not _change_alone(seen, change)):
        return finding
    peak = _furthest_after_alarm(change, seen.histories.time_s)
    if peak is None or peak[1] >= SLIGHT:
        return finding
    name, ratio = peak
    named = finding.component or " or ".join(finding.candidates) or "no single component"
    return replace(normal, verdict=Verdict.UNDETERMINED, case=None,
                   undetermined_because=f"an alarm too slight for {FEW_CHANGE_LOGS}").noted(
        f"a change-test alarm at {change.alarm_s:.1f} s (it named {named}) is not taken for "
        f"a fault: {name} reached {ratio:.2f} x its threshold at most, no other judge saw "
        f"anything, and the thresholds rest on {card.change_logs} normal log(s), whose "
        f"largest change the next normal log often passes this far; calibrate on "
        f"{SETTLED_LOGS} or more normal logs (auvdiag calibrate) to judge it")


def checks_quiet(seen: Observations) -> bool:
    """Whether the commands against the motion, the effort shares and the start stayed
    quiet on the log."""
    command, effort, start = seen.command_check, seen.effort_check, seen.start_check
    return ((command is None or command.alarm_s is None)
            and (effort is None or effort.alarm_s is None)
            and (start is None or not start.off))


def _change_alone(seen: Observations, change: ChangeCheck) -> bool:
    """Whether no judge but the change test alarmed: the replay's g stayed under its
    thresholds from the change's onset on, and the other checks stayed quiet."""
    if not checks_quiet(seen):
        return False
    ratio = judged_ratios(seen)
    if ratio is None:
        return True
    after = ratio[seen.histories.time_s >= (change.onset_s or change.alarm_s or 0.0)]
    return not bool(np.any(after[np.isfinite(after)] >= 1.0))


def _furthest_after_alarm(change: ChangeCheck, time_s: np.ndarray
                          ) -> tuple[str, float] | None:
    """The signal (or signature) whose statistic went furthest over its threshold from the
    alarm to the log's end, and how far; None where the test keeps no ratios."""
    ratios = change.ratios
    if ratios is None or not change.ratio_names:
        return None
    after = ratios[time_s >= (change.alarm_s or 0.0)]
    if not np.isfinite(after).any():
        return None
    peaks = np.nanmax(np.where(np.isfinite(after), after, -np.inf), axis=0)
    furthest = int(np.argmax(peaks))
    return change.ratio_names[furthest], float(peaks[furthest])
