"""The change test's thresholds (`engine.change_check`), set by `auvdiag calibrate` from
each judged signal's largest z on the normal logs."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.engine.change_check import REFERENCE_MIN_S, change_peaks
from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.jobs.budget import BudgetThresholds
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

# The change test's thresholds are never set below this z: over an hour's windows even
# Gaussian window means reach about 4 (sqrt(2 ln 2N)), residuals have heavier tails, and
# the largest of a handful of normal logs' peaks understates the next log's.
MIN_CHANGE_THRESHOLD_Z = 6.0


def log_change_peaks(diagnosis: Diagnosis, judged: Sequence[str], model: LoadedModel,
                  profile: Profile) -> dict[str, float]:
    """Each judged signal's largest change-test z in one normal log (NaN: too short)."""
    matching = diagnosis.histories.matching
    assert matching is not None
    names = list(profile.sensor_names)
    columns = [names.index(name) for name in judged]
    window = model.card.window_samples or profile.window_samples
    return change_peaks((matching.measured - matching.modelled)[:, columns], list(judged),
                        window, profile.dt_s)


def change_thresholds(peaks: Sequence[dict[str, float]], judged: Sequence[str],
                      margin: float, fitted: BudgetThresholds | None
                      ) -> dict[str, tuple[float, float]]:
    """Each signal's largest z and the change test's threshold: margin x the largest z on
    the normal logs, or the budget's where it fitted the judge, never below
    `MIN_CHANGE_THRESHOLD_Z`. A signal no log is long enough to judge gets none (the test
    leaves it out)."""
    budgeted = {} if fitted is None else {name: value for (_, name), value in
                                          fitted.thresholds("change").items()}
    result: dict[str, tuple[float, float]] = {}
    for name in judged:
        values = [p[name] for p in peaks if np.isfinite(p.get(name, np.nan))]
        if not values:
            continue
        largest = max(values)
        result[name] = (round(largest, 3), round(max(
            budgeted.get(name, margin * largest), MIN_CHANGE_THRESHOLD_Z), 3))
    return result


def change_entry(thresholds: dict[str, tuple[float, float]]) -> dict[str, object]:
    """model.json's `change_test` entry."""
    return {"thresholds": {name: threshold for name, (_, threshold) in thresholds.items()},
            "largest_normal_z": {name: largest for name, (largest, _) in thresholds.items()},
            "reference_s": REFERENCE_MIN_S}
