"""An alarm too slight for thresholds no calibration set: the replay's g crossed them by
little, and nothing else the tool judges saw anything.

A model used as trained judges by the profile's thresholds, raised by `train` to 1.5 times
the g of the logs it held out (one, of three). How far a normal log of the same missions
goes beyond that one log's g is unknown until the model is calibrated on normal logs: on
a simulated BlueROV2 trained on three missions, two of ten normal paper missions of other
noise seeds took the heave's g to 1.16 and 1.18 times the threshold so set (20.5 % and
20.9 % against 17.72 %) at the same manoeuvre, and no other judge departed. Such an
alarm is not taken for a fault: the verdict is undetermined, and the report says how far
the g went and what would judge it. An alarm the commands against the motion, the effort
shares, the change test or the start also raise stands; so does any alarm of a model
whose thresholds were calibrated (their false-alarm rate is then what calibrate says).
No fault of the simulated BlueROV2's mission scenarios, weakened thrusters included, was
found by the replay alone within SLIGHT of its thresholds."""

from dataclasses import replace

import numpy as np

from auvdiag_cli.engine.results import Finding, Observations, Verdict

# g that stays under this many times its uncalibrated threshold, from the onset on,
# decides nothing alone.
SLIGHT = 1.25
TOO_SLIGHT = "an alarm too slight for thresholds no calibration set"


def others_silent(seen: Observations) -> bool:
    """Whether every judge beside the replay stayed quiet on the log."""
    change, command, effort, start = (seen.change_check, seen.command_check,
                                      seen.effort_check, seen.start_check)
    return ((change is None or change.alarm_s is None)
            and (command is None or command.alarm_s is None)
            and (effort is None or effort.alarm_s is None)
            and (start is None or not start.off))


def beyond_slight(finding: Finding, normal: Finding, seen: Observations) -> Finding:
    """``finding``, or where it is a fault of a model whose thresholds no calibration set,
    raised by the replay alone and with its judged g under SLIGHT times its thresholds from
    the onset on, undetermined (``normal``'s notes), saying how far g went and what the
    alarm named."""
    model, histories = seen.model, seen.histories
    if (finding.verdict is not Verdict.FAULT or finding.onset_s is None
            or model.thresholds_calibrated or model.false_alarm_rate is not None
            or histories.matching is None or not others_silent(seen)):
        return finding
    names = histories.sensor_names
    judged = np.array([name not in seen.not_judged and name not in seen.set_aside
                       for name in names], bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(judged, histories.matching.g_percent / histories.thresholds, np.nan)
    after = ratio[histories.time_s >= finding.onset_s]
    if not np.isfinite(after).any():
        return finding
    peaks = np.nanmax(np.where(np.isfinite(after), after, -np.inf), axis=0)
    furthest = int(np.argmax(peaks))
    if peaks[furthest] >= SLIGHT:
        return finding
    named = finding.component or " or ".join(finding.candidates) or "no single component"
    return replace(normal, verdict=Verdict.UNDETERMINED, case=None,
                   undetermined_because=TOO_SLIGHT).noted(
        f"an alarm at {finding.detected_at_s or finding.onset_s:.1f} s (it named {named}) is "
        f"not taken for a fault: the replay's {names[furthest]} reached "
        f"{peaks[furthest]:.2f} x its threshold at most, no other judge saw anything, and "
        "the thresholds are the profile's or 1.5 x the g of the logs held out of training, "
        "which a normal log may pass this far; calibrate the model on normal logs "
        "(auvdiag calibrate) to judge it")
