"""The change test's largest statistics on the logs a model was trained on, kept in the model
(`models.change_training`) so that `calibrate` sets the change test's thresholds from them as
well as from its own logs.

The change test judges a log against its own beginning, in units of that log's own spread:
fitting the predictor to a log does not shrink that statistic the way it shrinks the
replay's g, so the logs the model was trained on are fair normal data for it (as their
starts are for the start check). With the two or three calibration logs a user often has,
they are what shows how far normal operation departs from its own beginning."""

from collections.abc import Callable, Sequence
from pathlib import Path

from auvdiag_cli.digest import log_digest
from auvdiag_cli.engine.change_columns import change_judged
from auvdiag_cli.engine.change_statistics import STRIDE_STEPS
from auvdiag_cli.engine.diagnosis import change_errors_of
from auvdiag_cli.engine.ingest import ingest
from auvdiag_cli.engine.judging import skilled
from auvdiag_cli.jobs.change_calibration import log_change_peaks
from auvdiag_cli.jobs.healthy import HealthyParts
from auvdiag_cli.vehicle.profile import Profile
from models.change_training import ChangeTraining, TrainedOnPeaks
from models.store import LoadedModel


def training_change_peaks(model: LoadedModel, profile: Profile, logs: Sequence[Path],
                          healthy: HealthyParts,
                          progress: Callable[[str], None] = lambda _: None) -> ChangeTraining:
    """Each log trained on (the part of it trained on) replayed by the new model, its
    largest change-test statistics; none where the change test judges nothing."""
    judged = change_judged(model, skilled(model, profile))
    if not judged:
        return ChangeTraining()
    progress(f"the change test on the {len(logs)} log(s) trained on (calibrate counts them)")
    return ChangeTraining(tuple(TrainedOnPeaks(path.name, log_digest(path), *log_change_peaks(
        *change_errors_of(ingest(path, profile, part=healthy.of(path)), profile, model),
        judged, model, profile)) for path in logs), STRIDE_STEPS, each_way=True)
