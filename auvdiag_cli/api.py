"""What a Python program may use: read a log, load a profile and a model, diagnose, write
the report, audit a fleet. Everything else inside auvdiag_cli may move between releases.

    from pathlib import Path
    from auvdiag_cli import api

    profile = api.load_profile("bluerov2_standard")    # a built-in name, a TOML path, or None
    model = api.load_model(Path("my_model"))            # None: the profile's shipped model
    diagnosis = api.diagnose(Path("dive.tlog"), profile, model)
    print(diagnosis.verdict, diagnosis.component, diagnosis.detected_at_s)
    report = api.to_json(diagnosis)                      # the JSON report, as a dict

Every failure is an `auvdiag_errors.AuvdiagError` (`LogError`, `ProfileError`, `ModelError`,
`UsageError`, …; import them from `auvdiag_errors`, their one home) whose message names the
file and the problem."""

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from adapters import read_log as _read_signals
from adapters.signals import Signals
from auvdiag_cli.audit.job import AuditOptions, AuditResult, run_audit
from auvdiag_cli.audit.progress import SilentReporter
from auvdiag_cli.engine.results import Diagnosis, Verdict
from auvdiag_cli.jobs.truth import diagnose_with_truth
from auvdiag_cli.reports.json_report import diagnosis_to_dict
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_cli.vehicle.profile import load_profile as _load_profile
from models.store import LoadedModel
from models.store import load_model as _load_model

__all__ = [
    "AuditResult", "Diagnosis", "LoadedModel", "Profile", "Signals", "Verdict", "audit",
    "diagnose", "load_model", "load_profile", "read_log", "to_json",
]


def load_profile(profile: str | Path | None = None) -> Profile:
    """A built-in profile by name (`auvdiag scenarios`' vehicles: twin_burger, bluerov2, …),
    a profile TOML file, or None for the Twin-Burger of the paper."""
    return _load_profile(None if profile is None else Path(profile))


def load_model(directory: Path | None = None, profile: Profile | None = None) -> LoadedModel:
    """A model directory (never runs code from it); None is the model shipped for the
    profile's vehicle (the Twin-Burger's without a profile), as the CLI picks it."""
    return _load_model(directory, profile.name if profile is not None else "twin-burger")


def read_log(path: Path, profile: Profile) -> Signals:
    """The profile's signals as the log holds them (each at its own rate, not resampled)."""
    return _read_signals(path, profile.sources)


def diagnose(path: Path, profile: Profile, model: LoadedModel,
             companions: Sequence[Path] = (), mission: Path | None = None) -> Diagnosis:
    """Diagnose one log. ``companions``: other logs of the same vehicle and day whose test
    sequences may decide between candidates; ``mission``: the mission plan for the
    closed-loop replay (default: NAME.mission.json beside the log)."""
    return diagnose_with_truth(path, profile, model, companions, mission)


def to_json(diagnosis: Diagnosis) -> dict[str, Any]:
    """The JSON report (docs/reports.md, the JSON report) as a dict."""
    return diagnosis_to_dict(diagnosis)


def audit(paths: Sequence[Path | str], output: Path, profile: Path | None = None,
          model: Path | None = None, jobs: int = 1) -> AuditResult:
    """Diagnose every log under ``paths`` (folders and globs) into ``output`` (one JSON
    report per log, audit.csv, fleet.pdf), resuming a finished part; no output while it
    runs. The result holds one record per log (``records``) and the counts."""
    return run_audit(AuditOptions([str(p) for p in paths], output, profile, model, jobs),
                     SilentReporter())
