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
effort shares, the change test or the start also raise, their event begun by its
detection, stands; so does one that crossed a threshold the profile set (its author's, not
a held-out log's: the shipped Twin-Burger's 15 %), and any alarm of a model whose
thresholds were calibrated (their false-alarm rate is then what calibrate says). Where the
other judges saw only a later event, the verdict is theirs. No fault of the simulated
BlueROV2's mission scenarios, weakened thrusters included, was found by the replay alone
within SLIGHT of its thresholds.

However far it crossed them, an alarm of the replay alone on such thresholds that no
single-component fault explains, but at most a sensor's reading fitted to the log after the
onset (an offset or a drift, which fits a model's own error as well), is not taken for a
fault either: a normal flight unlike those learnt from departs from the model so
(CrazyPAD, a model trained on four normal flights, its forward-speed threshold raised from
the one it held out: other normal flights took it to 2.4 and 2.7 times that, with every
rotor's share of the effort in its normal band, unexplained or "explained" by the state
estimate biased), and such a departure names nothing a user can act on. The verdict is
undetermined, saying how far g went; a fault another hypothesis explains stands.

Thresholds `calibrate` set on fewer than SETTLED_LOGS normal logs the model had not been
trained on rest on as little: the g of logs it was trained on is in-sample, widened by the
held-out / in-sample ratio of the one or two logs `train` held out. A simulated quadrotor
trained on four normal DataFlash logs and calibrated on the same four (one of them held
out of training) took the climb's g past those thresholds on 17 of 30 normal missions of
other noise seeds (9 of 30 calibrated to a budget of 1 %), all unexplained or "explained"
by a sensor's drift fitted to the log. Their alarms are judged as those of thresholds no
calibration set."""

from dataclasses import replace

import numpy as np

from auvdiag_cli.engine.envelope import within_the_envelope
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.near_effort import unless_not_ruled_out
from auvdiag_cli.engine.other_alarms import apply_change_alarm, apply_other_evidence
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.settled import SETTLED_LOGS, SLIGHT, judged_ratios, settled
from auvdiag_cli.engine.slight_change import beyond_slight_change, checks_quiet
from auvdiag_cli.vehicle.profile import Profile
from models.card import ModelCard, ModelIdentity

UNCALIBRATED = "thresholds no calibration set"
UNSETTLED = "thresholds calibrated on few logs the model had not seen"


def too_slight_for(basis: str) -> str:
    return f"an alarm too slight for {basis}"


def unexplained_on(basis: str) -> str:
    return f"an alarm no single fault explains but a fitted reading, on {basis}"


TOO_SLIGHT = too_slight_for(UNCALIBRATED)
UNEXPLAINED = unexplained_on(UNCALIBRATED)


def within_what_it_knows(finding: Finding, normal: Finding, seen: Observations,
                         judging: Judging, frame: AlignedFrame, profile: Profile) -> Finding:
    """``finding`` where the model can make it: not past the logs it learnt from
    (`envelope`), not on a slight crossing of thresholds its held-out logs set (``profile``:
    as given, its thresholds not the model's, as ``judging``'s are); where other judges
    alarmed only later, on what they saw (`before_later_judges`); not on a slight crossing
    of the change test's thresholds few logs set (`slight_change`); not normal where the
    effort shares cannot rule out a weak actuator (`near_effort`)."""
    card = judging.model.card
    finding = within_the_envelope(finding, normal, dict(card.envelope), judging.judged,
                                  frame)
    raised = set_by_logs(profile, card)
    later = later_judges_begin(seen, finding)
    if later is not None:
        finding = before_later_judges(finding, normal, seen, raised, judging, later)
    else:
        finding = beyond_slight(finding, normal, seen, raised)
    return unless_not_ruled_out(beyond_slight_change(finding, normal, seen, card), seen)


def set_by_logs(profile: Profile, card: ModelCard) -> frozenset[str]:
    """The signals whose threshold the model holds apart from the profile's in some mode:
    `train` raised it to its held-out logs' g, or `calibrate` set it from its normal logs
    (a settled calibration's alarms are not judged slight: `settled`)."""
    return frozenset(name for mode, limits in (card.thresholds or {}).items()
                     for name, value in limits.items()
                     if value != profile.thresholds_for(mode).get(name, value))


def _basis(model: ModelIdentity) -> str:
    """What the thresholds of a model not `settled` rest on."""
    return UNSETTLED if model.thresholds_calibrated else UNCALIBRATED


def others_silent(seen: Observations) -> bool:
    """Whether every judge beside the replay stayed quiet on the log."""
    change = seen.change_check
    return (change is None or change.alarm_s is None) and checks_quiet(seen)


def later_judges_begin(seen: Observations, finding: Finding) -> float | None:
    """Where the other judges that alarmed say their event began, the earliest of them,
    when every one of them began after the replay's detection (a later event, which does
    not bear the replay's alarm out); None where none alarmed or one began by then."""
    change, command, effort, start = (seen.change_check, seen.command_check,
                                      seen.effort_check, seen.start_check)
    if finding.detected_at_s is None or (start is not None and start.off):
        return None
    begins = [*([change.onset_s] if change is not None and change.alarm_s is not None
                else []),
              *([command.earliest_s] if command is not None and command.alarm_s is not None
                else [])]
    if effort is not None and effort.alarm_s is not None:
        begins.append(None if effort.onset_s is None
                      else effort.onset_s - (effort.onset_error_s or 0.0))
    if not begins or any(b is None or b <= finding.detected_at_s for b in begins):
        return None
    return min(b for b in begins if b is not None)


def before_later_judges(finding: Finding, normal: Finding, seen: Observations,
                        raised: frozenset[str], judging: Judging, later_s: float
                        ) -> Finding:
    """``finding``, or where the replay's alarm is slight until the other judges' event
    begins at ``later_s`` (`slight_peak`), or no single fault explains it (`unexplained`),
    the verdict of those judges alone, noting the alarm not taken: a normal stretch that
    crossed thresholds few unseen logs set takes nothing from a fault seen later (a
    simulated BlueROV2's heave at 1.04 x its threshold 36 s into a dive had named "thruster
    2 giving 50 %" a vertical thruster weakened at 90 s; a simulated quadrotor's climb at 2
    x its threshold 18 s into a flight, named nothing, had dated a rotor lost at 60 s
    there)."""
    slight = slight_peak(finding, seen, raised, later_s,
                         bound=np.inf if unexplained(finding) else SLIGHT)
    if slight is None:
        return finding
    name, ratio = slight
    normal = normal.noted(_not_taken(finding, seen.model, name, ratio,
                                     f"no other judge saw anything before {later_s:.1f} s, "
                                     "where the other judges' event begins")
                          + "; the verdict is theirs")
    change = seen.change_check
    if change is not None and change.alarm_s is not None:
        return apply_change_alarm(seen, normal, change, judging)
    return apply_other_evidence(seen, normal, judging)


def slight_peak(finding: Finding, seen: Observations, raised: frozenset[str],
                until_s: float = np.inf, bound: float = SLIGHT) -> tuple[str, float] | None:
    """Where ``finding`` is a fault of a model whose thresholds are not `settled` and its
    judged g stays under ``bound`` times its thresholds from the onset to ``until_s``, over
    them only in signals of ``raised`` (thresholds set from logs, not the profile's): the
    signal that went furthest and how far; else None."""
    model, histories = seen.model, seen.histories
    ratio = judged_ratios(seen)
    if (finding.verdict is not Verdict.FAULT or finding.onset_s is None
            or settled(model) or ratio is None):
        return None
    names = histories.sensor_names
    after = ratio[(histories.time_s >= finding.onset_s) & (histories.time_s < until_s)]
    if not np.isfinite(after).any():
        return None
    peaks = np.nanmax(np.where(np.isfinite(after), after, -np.inf), axis=0)
    furthest = int(np.argmax(peaks))
    crossed = {names[i] for i in np.flatnonzero(peaks >= 1.0)}
    if peaks[furthest] >= bound or not crossed <= raised:
        return None
    return names[furthest], float(peaks[furthest])


def unexplained(finding: Finding) -> bool:
    """Whether no hypothesis explains ``finding`` but a sensor's reading fitted to the log
    after the onset (`only_fitted`), and it names no other part."""
    test = finding.hypotheses
    named = {finding.component, *finding.candidates} - {None}
    return (test is not None and only_fitted(finding)
            and named <= {h.component for h in test.ranked if h.explains})


def only_fitted(finding: Finding) -> bool:
    """Whether no hypothesis explains the replay's departure but a sensor's reading fitted
    to the log after the onset (an offset or a drift, which absorbs whatever moved its
    signals: `hypotheses.FITTED_TO_THE_LOG`), whatever other judges named."""
    test = finding.hypotheses
    return test is not None and all(h.fitted for h in test.ranked if h.explains)


def _why_unexplained(finding: Finding) -> str:
    """How ``finding`` is explained, where `only_fitted`: by nothing, or only by a fit."""
    test = finding.hypotheses
    fits = [h.describe() for h in (test.ranked if test else ()) if h.explains]
    if not fits:
        return "no single-component fault explains it, "
    return (f"only a reading fitted to the log after the onset explains it ({fits[0]}), "
            "as it would a model's own error, ")


def _not_taken(finding: Finding, model: ModelIdentity, name: str, ratio: float,
               others: str = "no other judge saw anything") -> str:
    named = finding.component or " or ".join(finding.candidates) or "no single component"
    why = _why_unexplained(finding) if only_fitted(finding) else ""
    unseen = model.calibration_unseen_logs
    basis = ("are 1.5 x the g of the logs held out of training, which a normal log may pass "
             "this far; calibrate the model on normal logs (auvdiag calibrate) to judge it"
             if _basis(model) == UNCALIBRATED else
             f"rest on {unseen} normal log(s) the model was not trained on, which a normal "
             f"log may pass this far; calibrate it on {SETTLED_LOGS} or more normal logs it "
             "has not seen (auvdiag calibrate) to judge it")
    return (f"an alarm at {finding.detected_at_s or finding.onset_s:.1f} s (it named {named}) "
            f"is not taken for a fault: {why}the replay's {name} reached {ratio:.2f} x its "
            f"threshold at most, {others}, and the thresholds it crossed {basis}")


def beyond_slight(finding: Finding, normal: Finding, seen: Observations,
                  raised: frozenset[str]) -> Finding:
    """``finding``, or where it is a fault raised by the replay alone whose g is slight
    from the onset on (`slight_peak`), or that no hypothesis explains however far g went,
    undetermined (``normal``'s notes), saying how far g went and what the alarm named."""
    alone = unexplained(finding)
    slight = slight_peak(finding, seen, raised, bound=np.inf if alone else SLIGHT) \
        if others_silent(seen) else None
    if slight is None:
        return finding
    basis = _basis(seen.model)
    return replace(normal, verdict=Verdict.UNDETERMINED, case=None,
                   undetermined_because=(unexplained_on if alone else too_slight_for)(basis)
                   ).noted(
        _not_taken(finding, seen.model, *slight))
