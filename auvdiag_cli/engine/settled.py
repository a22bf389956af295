"""How far thresholds set from a few logs can be trusted: what the replay's alarm must show
before it is taken for a fault where they rest on few normal logs (`slight_alarm`)."""

import numpy as np

from auvdiag_cli.engine.results import Observations
from models.card import ModelIdentity

# A statistic that stays under this many times a threshold few logs set decides nothing
# alone.
SLIGHT = 1.25
# Set on fewer normal logs than this (for the replay's g, logs the model was not trained
# on), thresholds are not settled: the largest of so few is often passed by the next
# normal log.
SETTLED_LOGS = 5


def settled(model: ModelIdentity) -> bool:
    """Whether ``model``'s thresholds were calibrated on SETTLED_LOGS normal logs or more
    that it was not trained on (a calibration from before that count was kept: settled)."""
    unseen = model.calibration_unseen_logs
    return ((model.thresholds_calibrated or model.false_alarm_rate is not None)
            and (unseen is None or unseen >= SETTLED_LOGS))


def judged_ratios(seen: Observations) -> np.ndarray | None:
    """(steps, signals): each signal's g over its threshold, NaN where the replay does not
    judge it; None where the log was not replayed."""
    histories = seen.histories
    if histories.matching is None:
        return None
    judged = np.array([name not in seen.not_judged and name not in seen.set_aside
                       for name in histories.sensor_names], bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(np.where(judged, histories.matching.g_percent
                                   / histories.thresholds, np.nan))
