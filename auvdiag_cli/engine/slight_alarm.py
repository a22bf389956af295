"""An alarm too slight for thresholds no calibration set: the replay's g crossed by little
thresholds that rest on the logs `train` held out, and nothing else the tool judges saw
anything.

A model used as trained judges by the profile's thresholds, raised by `train` to 1.5 times
the g of the logs it held out (one, of three) where that is more. How far a normal log of
the same missions goes beyond that one log's g is unknown until the model is calibrated on
normal logs: on a simulated BlueROV2 trained on three missions, two of ten normal paper
missions of other noise seeds took the heave's g to 1.16 and 1.18 times the threshold so
set (20.5 % and 20.9 % against 17.72 %) at the same manoeuvre, and no other judge departed.
Such an alarm is not taken for a fault: the verdict is undetermined, and the report says
how far the g went and what would judge it. An alarm the commands against the motion, the
effort shares, the change test or the start also raise stands; so does one that crossed a
threshold the profile set (its author's, not a held-out log's: the shipped Twin-Burger's
15 %), and any alarm of a model whose thresholds were calibrated (their false-alarm rate is
then what calibrate says). No fault of the simulated BlueROV2's mission scenarios, weakened
thrusters included, was found by the replay alone within SLIGHT of its thresholds."""

from dataclasses import replace

import numpy as np

from auvdiag_cli.engine.envelope import within_the_envelope
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.vehicle.profile import Profile
from models.card import ModelCard

# g that stays under this many times its uncalibrated threshold, from the onset on,
# decides nothing alone.
SLIGHT = 1.25
TOO_SLIGHT = "an alarm too slight for thresholds no calibration set"


def within_what_it_knows(finding: Finding, normal: Finding, seen: Observations,
                         judging: Judging, frame: AlignedFrame, profile: Profile) -> Finding:
    """``finding`` where the model can make it: not past the logs it learnt from
    (`envelope`), not on a slight crossing of thresholds its held-out logs set (``profile``:
    as given, its thresholds not the model's, as ``judging``'s are)."""
    card = judging.model.card
    return beyond_slight(within_the_envelope(finding, normal, dict(card.envelope),
                                             judging.judged, frame),
                         normal, seen, raised_by_training(profile, card))


def raised_by_training(profile: Profile, card: ModelCard) -> frozenset[str]:
    """The signals whose threshold the model holds above the profile's in some mode:
    `train` raised it to its held-out logs' g (calibrate's thresholds count too, but a
    calibrated model's alarms are not judged slight)."""
    return frozenset(name for mode, limits in (card.thresholds or {}).items()
                     for name, value in limits.items()
                     if value > profile.thresholds_for(mode).get(name, value))


def others_silent(seen: Observations) -> bool:
    """Whether every judge beside the replay stayed quiet on the log."""
    change, command, effort, start = (seen.change_check, seen.command_check,
                                      seen.effort_check, seen.start_check)
    return ((change is None or change.alarm_s is None)
            and (command is None or command.alarm_s is None)
            and (effort is None or effort.alarm_s is None)
            and (start is None or not start.off))


def beyond_slight(finding: Finding, normal: Finding, seen: Observations,
                  raised: frozenset[str]) -> Finding:
    """``finding``, or where it is a fault of a model whose thresholds no calibration set,
    raised by the replay alone, its judged g under SLIGHT times its thresholds from the
    onset on and over them only in signals of ``raised`` (thresholds `train` raised),
    undetermined (``normal``'s notes), saying how far g went and what the alarm named."""
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
    crossed = {names[i] for i in np.flatnonzero(peaks >= 1.0)}
    if peaks[furthest] >= SLIGHT or not crossed <= raised:
        return finding
    named = finding.component or " or ".join(finding.candidates) or "no single component"
    return replace(normal, verdict=Verdict.UNDETERMINED, case=None,
                   undetermined_because=TOO_SLIGHT).noted(
        f"an alarm at {finding.detected_at_s or finding.onset_s:.1f} s (it named {named}) is "
        f"not taken for a fault: the replay's {names[furthest]} reached "
        f"{peaks[furthest]:.2f} x its threshold at most, no other judge saw anything, and "
        "the thresholds it crossed are 1.5 x the g of the logs held out of training, which a "
        "normal log may pass this far; calibrate the model on normal logs (auvdiag "
        "calibrate) to judge it")
