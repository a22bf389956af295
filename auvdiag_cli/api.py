"""What a Python program may use: every command of the CLI as a function, on objects
(profiles, models, diagnoses) rather than paths where the CLI takes paths. Everything else
inside auvdiag_cli may move between releases.

    from pathlib import Path
    from auvdiag_cli import api

    profile = api.load_profile("bluerov2_standard")    # a built-in name, a TOML path, or None
    model = api.load_model(profile=profile)             # the profile's shipped model
    diagnosis = api.diagnose(Path("dive.tlog"), profile, model)
    print(diagnosis.verdict, diagnosis.component, diagnosis.detected_at_s)
    api.write_reports(diagnosis, pdf=Path("dive.pdf"), json=Path("dive.json"))

    result = api.train([Path("day1")], Path("my_model"), profile)    # a folder of dives
    model = api.load_model(Path("my_model"), profile)
    api.calibrate(model, profile, [Path("day2")], budget=api.FalseAlarmBudget(0.05))
    api.save_model(model, Path("my_model"))

Every failure is an `auvdiag_errors.AuvdiagError` (`LogError`, `ProfileError`, `ModelError`,
`UsageError`, …; import them from `auvdiag_errors`, their one home) whose message names the
file and the problem. Nothing here prints or imports a terminal library; long work reports
through ``progress`` (a function taking one line of text) where it is given."""

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from adapters import read_log as _read_signals
from adapters.signals import Signals
from auvdiag_cli.audit.discovery import expand_logs
from auvdiag_cli.audit.job import AuditOptions, AuditResult, run_audit
from auvdiag_cli.audit.progress import SilentReporter
from auvdiag_cli.audit.trend import FleetTrend, trend_of_audit
from auvdiag_cli.engine.results import Diagnosis, Verdict
from auvdiag_cli.files import write_json
from auvdiag_cli.jobs.budget import FalseAlarmBudget
from auvdiag_cli.jobs.calibrate import CalibrationResult
from auvdiag_cli.jobs.calibrate import calibrate as _calibrate
from auvdiag_cli.jobs.inspect import Inspection, inspect_log
from auvdiag_cli.jobs.profile_draft import draft_profile as _draft_profile
from auvdiag_cli.jobs.relate import relate_model
from auvdiag_cli.jobs.train import (
    DEFAULT_TRAINING,
    TrainingResult,
    TrainOptions,
    score_model,
    train_from_logs,
)
from auvdiag_cli.jobs.truth import diagnose_with_truth
from auvdiag_cli.reports.json_report import diagnosis_to_dict
from auvdiag_cli.reports.series import save_series, series_from_diagnosis, series_path
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_cli.vehicle.profile import load_profile as _load_profile
from models.card import ModelCard
from models.skill import HorizonScore
from models.store import LoadedModel, write_model
from models.store import load_model as _load_model

__all__ = [
    "AuditResult", "CalibrationResult", "Diagnosis", "FalseAlarmBudget", "FleetTrend",
    "HorizonScore", "Inspection", "LoadedModel", "ModelCard", "Profile", "Signals",
    "TrainOptions", "TrainingResult", "Verdict", "audit", "calibrate", "diagnose",
    "draft_profile", "inspect", "load_model", "load_profile", "read_log", "relate",
    "save_model", "score", "to_json", "train", "trend", "write_reports",
]

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    """No progress reports."""


def load_profile(profile: str | Path | None = None) -> Profile:
    """A built-in profile by name (`auvdiag scenarios`' vehicles: twin_burger, bluerov2, …),
    a profile TOML file, or None for the Twin-Burger of the paper."""
    return _load_profile(None if profile is None else Path(profile))


def load_model(directory: Path | None = None, profile: Profile | None = None) -> LoadedModel:
    """A model directory (never runs code from it); None is the model shipped for the
    profile's vehicle (the Twin-Burger's without a profile), as the CLI picks it. Its typed
    model card is ``model.card``."""
    return _load_model(directory, profile.name if profile is not None else "twin-burger")


def save_model(model: LoadedModel, directory: Path) -> None:
    """Write a model that `calibrate`, `relate` or `score` updated (atomically); a directory
    other than its own gets its weights too."""
    write_model(model, directory)


def read_log(path: Path, profile: Profile) -> Signals:
    """The profile's signals as the log holds them (each at its own rate, not resampled)."""
    return _read_signals(path, profile.sources)


def inspect(path: Path, profile: Profile) -> Inspection:
    """What the log holds (topics, rates, span) and which of the profile's signals resolve
    in it: `auvdiag inspect`."""
    return inspect_log(path, profile)


def draft_profile(path: Path, name: str) -> str:
    """The TOML text of a starting profile for the vehicle that wrote the log at ``path``
    (fields it cannot place are marked CHECK): `auvdiag init-profile`."""
    return _draft_profile(path, name)


def train(logs: Sequence[Path], output: Path, profile: Profile,
          options: TrainOptions = DEFAULT_TRAINING, progress: Progress = _quiet
          ) -> TrainingResult:
    """Train on normal ``logs`` (files or folders of them) and write the model directory
    ``output`` where it judges anything (``options.keep_unskilled``: always). The result
    holds each signal's skill, the horizon and the predictor chosen: `auvdiag train`."""
    return train_from_logs(expand_logs(logs, progress), output, profile, options, progress)


def score(model: LoadedModel, profile: Profile, logs: Sequence[Path],
          horizon_s: float | None = None, progress: Progress = _quiet) -> HorizonScore:
    """Measure the model's skill on normal logs it was not trained on, and record it in the
    model (write it with `save_model`); returns the horizon chosen, with every signal's
    skill: `auvdiag score`."""
    return score_model(model, profile, logs, horizon_s, progress)[1]


def relate(model: LoadedModel, profile: Profile, logs: Sequence[Path],
           holdout: Sequence[Path] = (), progress: Progress = _quiet) -> None:
    """Learn how the commands follow the motion and where normal logs start, into the model
    (write it with `save_model`): `auvdiag relate`."""
    relate_model(model, profile, logs, holdout, progress)


def calibrate(model: LoadedModel, profile: Profile, normal_logs: Sequence[Path],
              faulty_logs: Sequence[Path] = (), margin: float = 1.5,
              budget: FalseAlarmBudget | None = None, floor_at_profile: bool = False,
              progress: Progress = _quiet) -> CalibrationResult:
    """Set the model's thresholds from normal logs, by ``margin`` x the largest g or to a
    false-alarm ``budget``; the model is updated (write it with `save_model`): `auvdiag
    calibrate`."""
    return _calibrate(model, profile, normal_logs, faulty_logs, margin, floor_at_profile,
                      budget, progress)


def diagnose(path: Path, profile: Profile, model: LoadedModel,
             companions: Sequence[Path] = (), mission: Path | None = None) -> Diagnosis:
    """Diagnose one log. ``companions``: other logs of the same vehicle and day whose test
    sequences may decide between candidates; ``mission``: the mission plan for the
    closed-loop replay (default: NAME.mission.json beside the log)."""
    return diagnose_with_truth(path, profile, model, companions, mission)


def to_json(diagnosis: Diagnosis) -> dict[str, Any]:
    """The JSON report (docs/reports.md, the JSON report) as a dict."""
    return diagnosis_to_dict(diagnosis)


def write_reports(diagnosis: Diagnosis, json: Path | None = None, pdf: Path | None = None,
                  mcap: Path | None = None) -> None:
    """Write the diagnosis as a JSON report (with its time histories beside it, which
    `auvdiag report` redraws from), a PDF and an MCAP for Foxglove, as many as are asked."""
    document, series = diagnosis_to_dict(diagnosis), series_from_diagnosis(diagnosis)
    if json is not None:
        sidecar = series_path(json)
        save_series(series, sidecar)
        write_json({**document, "series_file": sidecar.name}, json)
    if pdf is not None:
        from auvdiag_cli.reports.pdf.dive import render_dive_report

        render_dive_report(document, series, pdf)
    if mcap is not None:
        from auvdiag_cli.reports.mcap_export import write_diagnosis_mcap

        write_diagnosis_mcap(document, series, mcap)


def _reference(profile: Profile) -> Path:
    """How a worker process loads the same profile: its file, or its built-in name."""
    where = profile.source_path
    return Path(where.removeprefix("builtin:"))


def audit(paths: Sequence[Path | str], output: Path, profile: Profile | None = None,
          model: LoadedModel | None = None, jobs: int = 1, mcap: bool = False) -> AuditResult:
    """Diagnose every log under ``paths`` (folders and globs) into ``output`` (one JSON
    report per log, audit.csv, fleet.pdf), resuming a finished part; nothing is printed.
    ``model``: a model read from a directory (None: the profile's shipped model). The
    result holds one record per log (``records``) and the counts."""
    if model is not None and model.directory is None:
        raise ValueError("audit needs a model read from a directory (api.load_model)")
    return run_audit(AuditOptions([str(p) for p in paths], output,
                                  None if profile is None else _reference(profile),
                                  None if model is None else model.directory, jobs, mcap=mcap),
                     SilentReporter())


def trend(audit_dir: Path, last: int = 8, alpha: float = 0.05) -> FleetTrend:
    """Per vehicle and signal, whether the margin to the thresholds shrinks over the last
    ``last`` dives of an audit (Mann-Kendall at ``alpha``): `auvdiag trend`."""
    return trend_of_audit(audit_dir, last, alpha)
