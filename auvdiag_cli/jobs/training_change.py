"""The change test's largest statistics on the logs a model was trained on, kept in the model
(model.json `change_training`) so that `calibrate` sets the change test's thresholds from
them as well as from its own logs.

The change test judges a log against its own beginning, in units of that log's own spread:
fitting the predictor to a log does not shrink that statistic the way it shrinks the
replay's g, so the logs the model was trained on are fair normal data for it (as their
starts are for the start check). With the two or three calibration logs a user often has,
they are what shows how far normal operation departs from its own beginning: on simulated
BlueROV2 missions, two calm calibration missions left the yaw rate's thresholds at the
margin rule's floor, which the training missions' turns (and half of ten normal missions of
other seeds) went past."""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from auvdiag_cli.digest import log_digest
from auvdiag_cli.engine.change_check import change_judged
from auvdiag_cli.engine.diagnosis import diagnose_ingested
from auvdiag_cli.engine.ingest import ingest
from auvdiag_cli.engine.judging import skilled
from auvdiag_cli.jobs.change_calibration import log_change_peaks
from auvdiag_cli.jobs.healthy import HealthyParts
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

ENTRY = "change_training"
# statistic -> signal (or signature) -> the log's largest value (NaN: not judged there)
Peaks = dict[str, dict[str, float]]


@dataclass(frozen=True)
class TrainingPeaks:
    """One training log's largest change-test statistics."""

    log: str
    sha256: str
    peaks: Peaks


def training_change_entry(model: LoadedModel, profile: Profile, logs: Sequence[Path],
                          healthy: HealthyParts,
                          progress: Callable[[str], None] = lambda _: None
                          ) -> dict[str, object]:
    """model.json's `change_training`: each training log (the part of it trained on)
    diagnosed with the new model, its largest change-test statistics. Empty where the
    change test judges nothing."""
    judged = change_judged(model, skilled(model, profile))
    if not judged:
        return {"logs": []}
    progress(f"the change test on the {len(logs)} log(s) trained on (calibrate counts them)")
    base = model.with_entries(thresholds=profile.thresholds)
    entries = []
    for path in logs:
        diagnosis = diagnose_ingested(ingest(path, profile, part=healthy.of(path)), profile,
                                      base)
        peaks = log_change_peaks(diagnosis, judged, model, profile)
        entries.append({"log": path.name, "sha256": log_digest(path), "peaks": {
            statistic: {name: value if np.isfinite(value) else None
                        for name, value in values.items()}
            for statistic, values in peaks.items()}})
    return {"logs": entries}


def stored_training_peaks(model: LoadedModel, leave_out: Sequence[str] = ()
                          ) -> list[TrainingPeaks]:
    """The training logs' peaks the model keeps, but those whose digest is in ``leave_out``
    (calibration logs that were trained on: calibrate reads them itself)."""
    found = []
    for entry in model.card.entry(ENTRY).get("logs", []):
        if str(entry.get("sha256")) in leave_out:
            continue
        found.append(TrainingPeaks(str(entry.get("log")), str(entry.get("sha256")), {
            str(statistic): {str(name): float("nan") if value is None else float(value)
                             for name, value in values.items()}
            for statistic, values in (entry.get("peaks") or {}).items()}))
    return found
