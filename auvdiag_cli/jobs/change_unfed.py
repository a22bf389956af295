"""The change test's thresholds for a log that does not feed one of the model's inputs
(a dead airspeed sensor, a topic not recorded), set by `auvdiag calibrate`.

Such a log is replayed with that input held at its typical value, so its predictor errs
where the input would have told it something: an aircraft's climb, which follows its
airspeed, departs further from its prediction than on any log that fed it. Judged against
thresholds set on logs that fed it, a normal flight without airspeed alarmed on its climb
(ALFA). So calibrate also replays each of its normal logs that fed the input with it held
at its typical value and, beside those, takes the normal logs that never fed it as they
are (on ALFA a whole flying day logged no airspeed: left out, such a flight's thresholds
rested on half the logs), and sets the change test's thresholds on them the same way (the
same share of the budget for each judge, or the margin rule); a log without that input is
judged by the larger of the two. A loop's gain (`models.tracking`) is read from the log's
set points and sensors, never from the model, so holding an input leaves it as it was: its
thresholds stay the fed ones (on ALFA, the roll loop's threshold for flights without
airspeed had risen 17 % from fewer logs alone, and left a stuck aileron under it)."""

from collections.abc import Callable, Sequence
from dataclasses import replace

from auvdiag_cli.engine.change_columns import change_judged, loop_names
from auvdiag_cli.engine.change_signatures import thresholded
from auvdiag_cli.engine.change_statistics import WayScales
from auvdiag_cli.engine.diagnosis import change_errors_of
from auvdiag_cli.engine.ingest import IngestedLog
from auvdiag_cli.engine.judging import skilled
from auvdiag_cli.jobs.budget import BudgetThresholds, change_judges, refitted
from auvdiag_cli.jobs.change_calibration import (
    ChangeEvidence,
    ChangeThresholds,
    change_thresholds,
    either_way,
    enough_judged,
    log_change_peaks,
    without_outliers,
)
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

# input -> statistic -> signal -> threshold
UnfedThresholds = dict[str, dict[str, dict[str, float]]]


def held(log: IngestedLog, name: str) -> IngestedLog:
    """The log as if it had not fed input ``name`` (the diagnosis then holds it at its
    typical value)."""
    frame = log.frame
    return IngestedLog(log.signals, replace(frame, flat_inputs={
        **frame.flat_inputs, name: "held at its typical value by calibrate"}))


def unfed_thresholds(logs: Sequence[IngestedLog], model: LoadedModel, profile: Profile,
                     margin: float, fitted: BudgetThresholds | None, scales: WayScales,
                     fed: ChangeThresholds,
                     progress: Callable[[str], None] = lambda _: None) -> UnfedThresholds:
    """Per model input, the change test's thresholds on the normal ``logs`` as judged
    without it: those that fed it replayed with it held, the others as they are (only where
    that raises them above ``fed``, the thresholds with it fed)."""
    loops = loop_names(model)
    judged = [n for n in change_judged(model, skilled(model, profile)) if n not in loops]
    if not judged or not fed:
        return {}
    result: UnfedThresholds = {}
    for name in model.card.input_names:
        feeding = [_feeds(log, name) for log in logs]
        if not any(feeding):
            continue
        progress(f"the change test with {name} held, on {sum(feeding)} normal log(s)"
                 + ("" if all(feeding) else f" and {len(logs) - sum(feeding)} without it"))
        # A normal log that never fed the input is one as judged without it already.
        peaks = [log_change_peaks(*change_errors_of(held(log, name) if feeds else log,
                                                    profile, model), judged, model, profile)
                 for log, feeds in zip(logs, feeding, strict=True)]
        evidence = without_outliers(enough_judged(ChangeEvidence(
            thresholded(profile.actuators, profile.sensors, judged),
            [either_way(p, judged, scales) for p, _ in peaks], scales=scales),
            [seconds for _, seconds in peaks]))
        budget = None if fitted is None else refitted(
            fitted, change_judges(evidence.peaks, evidence.judged))
        raised = _above(change_thresholds(evidence, margin, budget), fed)
        if raised:
            result[name] = raised
    return result


def _feeds(log: IngestedLog, name: str) -> bool:
    return name in log.frame.input_names and name not in log.frame.flat_inputs


def _above(unfed: ChangeThresholds, fed: ChangeThresholds) -> dict[str, dict[str, float]]:
    """statistic -> signal -> the unfed threshold where it is above the fed one."""
    raised: dict[str, dict[str, float]] = {}
    for statistic, values in unfed.items():
        for signal, (_, threshold) in values.items():
            if signal in fed.get(statistic, {}) and threshold > fed[statistic][signal][1]:
                raised.setdefault(statistic, {})[signal] = threshold
    return raised
