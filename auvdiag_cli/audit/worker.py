"""One log's diagnosis as a self-contained task: what a local process or a Dask worker runs.
Tasks and outcomes are plain picklable values; the model is loaded once per worker process."""

import os
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.peak_memory import peak_rss_mb
from auvdiag_errors import AuvdiagError


@dataclass(frozen=True)
class AuditTask:
    log: str
    profile: str | None          # path or built-in name; None: the default profile
    model: str | None            # model directory; None: the profile's shipped model


@dataclass
class AuditOutcome:
    log: str
    document: dict[str, Any] | None
    series: dict[str, np.ndarray] = field(default_factory=dict)
    error: str | None = None     # one line: why the log could not be analysed
    final: bool = True           # False: a failure of the run, not of the log (retry later)
    seconds: float = 0.0
    peak_rss_mb: float = 0.0


@cache
def _profile_and_model(profile: str | None, model: str | None) -> tuple[Any, Any]:
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    vehicle = load_profile(None if profile is None else Path(profile))
    return vehicle, load_model(None if model is None else Path(model), vehicle.name)


def analyse(task: AuditTask) -> AuditOutcome:
    """Diagnose one log; never raises (a failure is the outcome's ``error``)."""
    from auvdiag_cli.engine.diagnosis import diagnose
    from auvdiag_cli.reports.json_report import diagnosis_to_dict
    from auvdiag_cli.reports.series import series_from_diagnosis
    from models.fast import replaying_many_logs

    started = time.perf_counter()
    outcome = AuditOutcome(task.log, None)
    try:
        profile, model = _profile_and_model(task.profile, task.model)
        with replaying_many_logs():
            result = diagnose(Path(task.log), profile, model)
        outcome.document = diagnosis_to_dict(result)
        outcome.series = series_from_diagnosis(result)
    except AuvdiagError as error:
        outcome.error = str(error)
    except MemoryError:
        outcome.error, outcome.final = f"{task.log}: out of memory", False
    except Exception as error:  # a bug must not take the batch down; the row says what
        if os.environ.get("AUVDIAG_DEBUG"):
            raise
        outcome.error = f"{task.log}: unexpected {type(error).__name__}: {error}"
        outcome.final = False
    outcome.seconds = round(time.perf_counter() - started, 3)
    outcome.peak_rss_mb = round(peak_rss_mb(), 1)
    return outcome
