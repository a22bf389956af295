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

    result = api.train([Path("day1")], profile, Path("my_model"))    # a folder of dives
    model = api.load_model(Path("my_model"), profile)
    budget = api.CalibrateOptions(budget=api.FalseAlarmBudget(0.05))
    api.calibrate([Path("day2")], profile, model, options=budget)
    api.save_model(model, Path("my_model"))

Every function takes what it reads first (a log, logs), then the vehicle (profile, model),
then where it writes; options are keywords.

Every failure is an `auvdiag_errors.AuvdiagError` (`LogError`, `ProfileError`, `ModelError`,
`UsageError`, …; import them from `auvdiag_errors`, their one home) whose message names the
file and the problem. Nothing here prints or imports a terminal library; long work reports
through ``progress`` (a function taking one line of text) where it is given."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from importlib import import_module
from pathlib import Path
from typing import TYPE_CHECKING, Any

from auvdiag_errors import UsageError

if TYPE_CHECKING:
    from adapters.signals import Signals
    from auvdiag_cli.audit.job import AuditResult
    from auvdiag_cli.audit.progress import Reporter
    from auvdiag_cli.audit.record import AuditRecord
    from auvdiag_cli.audit.trend import FleetTrend
    from auvdiag_cli.engine.results import Diagnosis, Verdict
    from auvdiag_cli.engine.signatures import DerivedTable
    from auvdiag_cli.jobs.budget import FalseAlarmBudget
    from auvdiag_cli.jobs.calibrate import CalibrateOptions
    from auvdiag_cli.jobs.calibration_result import CalibrationResult
    from auvdiag_cli.jobs.healthy import HealthyParts, read_healthy_parts
    from auvdiag_cli.jobs.inspect import Inspection
    from auvdiag_cli.jobs.train import TrainingResult, TrainOptions
    from auvdiag_cli.reports.report import Report
    from auvdiag_cli.reports.saved import redraw_report
    from auvdiag_cli.simulator.run import SimulatedDive
    from auvdiag_cli.simulator.scenarios import Scenario
    from auvdiag_cli.vehicle.profile import Profile
    from models.card import ModelCard, Refused, StartReference
    from models.command_relations import CommandRelations
    from models.effort_model import EffortModel
    from models.skill import HorizonScore
    from models.store import LoadedModel
    from models.thrust_relations import ThrustRelations

    AuditProgress = Reporter


__all__ = [
    "AuditProgress", "AuditRecord", "AuditResult", "CalibrateOptions", "CalibrationResult",
    "CommandRelations", "DerivedTable", "Diagnosis", "EffortModel", "FalseAlarmBudget",
    "FleetTrend", "HealthyParts", "HorizonScore", "Inspection", "LoadedModel", "ModelCard",
    "Profile", "Refused", "Report", "Scenario", "Signals", "SimulatedDive", "StartReference",
    "ThrustRelations", "TrainOptions", "TrainingResult", "Verdict", "audit", "build_report",
    "calibrate",
    "derive_table", "diagnose", "draft_profile", "inspect", "load_model", "load_profile",
    "log_format", "read_healthy_parts", "read_log", "redraw_report", "relate", "save_model",
    "scenarios", "score", "simulate", "summary_text", "to_json", "train", "trend", "write_reports",
]


# The classes (and one function) this module hands out, each imported from its home
# ("module.name") on first use, so that a diagnosis imports no training, audit or simulator.
_EXPORTED = {name: f"{module}.{name}" for module, names in {
    "adapters.signals": ["Signals"],
    "auvdiag_cli.audit.job": ["AuditResult"],
    "auvdiag_cli.audit.record": ["AuditRecord"],
    "auvdiag_cli.audit.trend": ["FleetTrend"],
    "auvdiag_cli.engine.results": ["Diagnosis", "Verdict"],
    "auvdiag_cli.engine.signatures": ["DerivedTable"],
    "auvdiag_cli.jobs.budget": ["FalseAlarmBudget"],
    "auvdiag_cli.jobs.calibrate": ["CalibrateOptions", "CalibrationResult"],
    "auvdiag_cli.jobs.healthy": ["HealthyParts", "read_healthy_parts"],
    "auvdiag_cli.jobs.inspect": ["Inspection"],
    "auvdiag_cli.jobs.train": ["TrainOptions", "TrainingResult"],
    "auvdiag_cli.reports.report": ["Report"],
    "auvdiag_cli.reports.saved": ["redraw_report"],
    "auvdiag_cli.simulator.run": ["SimulatedDive"],
    "auvdiag_cli.simulator.scenarios": ["Scenario"],
    "auvdiag_cli.vehicle.profile": ["Profile"],
    "models.card": ["ModelCard", "Refused", "StartReference"],
    "models.command_relations": ["CommandRelations"],
    "models.effort_model": ["EffortModel"],
    "models.skill": ["HorizonScore"],
    "models.thrust_relations": ["ThrustRelations"],
    "models.store": ["LoadedModel"],
}.items() for name in names}
# start(total, reused), done(record), stop(): an audit's progress
_EXPORTED["AuditProgress"] = "auvdiag_cli.audit.progress.Reporter"


def __getattr__(name: str) -> Any:
    if name not in _EXPORTED:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, _, attribute = _EXPORTED[name].rpartition(".")
    value = getattr(import_module(module), attribute)
    globals()[name] = value
    return value


Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    """No progress reports."""


def load_profile(profile: str | Path | None = None, *, model: Path | None = None) -> Profile:
    """A built-in profile by name (`auvdiag scenarios`' vehicles: twin_burger, bluerov2, …),
    a profile TOML file, or None: the profile ``model`` (a model directory) was trained
    with, as its model.json records it, else the Twin-Burger of the paper."""
    from auvdiag_cli.vehicle.profile import load_profile as read_profile
    from models.store import trained_profile

    if profile is None and model is not None:
        profile = trained_profile(model)
    return read_profile(None if profile is None else Path(profile))


def load_model(directory: Path | None = None, profile: Profile | None = None) -> LoadedModel:
    """A model directory (never runs code from it); None is the model shipped for the
    profile's vehicle (the Twin-Burger's without a profile), as the CLI picks it. Its typed
    model card is ``model.card``."""
    from models.store import load_model as read_model

    return read_model(directory, profile.name if profile is not None else "twin-burger")


def save_model(model: LoadedModel, directory: Path) -> None:
    """Write a model that `calibrate`, `relate` or `score` updated (atomically); a directory
    other than its own gets its weights too."""
    from models.store import write_model

    write_model(model, directory)


def log_format(path: Path) -> str:
    """The format of the log at ``path`` by its content (bag, db3, mcap, tlog, bin, ulog,
    alog, csv, …); a `LogError` naming the file where it is not a log this tool reads."""
    from adapters import detect_format

    return detect_format(path)


def read_log(path: Path, profile: Profile) -> Signals:
    """The profile's signals as the log holds them (each at its own rate, not resampled)."""
    from adapters import read_log as read_signals

    return read_signals(path, profile.sources)


def inspect(path: Path, profile: Profile | None = None) -> Inspection:
    """What the log holds (topics, rates, span) and which of the profile's signals resolve
    in it (None: what it holds only): `auvdiag inspect`."""
    from auvdiag_cli.jobs.inspect import inspect_log

    return inspect_log(path, profile)


def draft_profile(path: Path, name: str | None = None, like: str | Path | None = None,
                  closed_loop: bool = False) -> str:
    """The TOML text of a starting profile for the vehicle that wrote the log at ``path``
    (fields it cannot place are marked CHECK; ``name`` defaults to the log's), or with
    ``like`` that profile (a file or a built-in name) with its mapping fitted to the log;
    ``closed_loop``: the model driven by the controller's set points (ArduPilot's ATT,
    RATE, CTUN), the motor outputs read for the effort check only: `auvdiag init-profile`."""
    from auvdiag_cli.jobs.profile_draft import draft_profile as draft
    from auvdiag_cli.jobs.profile_like import draft_like

    if like is not None:
        if closed_loop:
            raise UsageError("--closed-loop drafts from the log; with --like the profile "
                             "says what drives its model")
        return draft_like(path, Path(like))
    return draft(path, name or path.stem, closed_loop)


def train(logs: Sequence[Path], profile: Profile, output: Path, *,
          options: TrainOptions | None = None, progress: Progress = _quiet
          ) -> TrainingResult:
    """Train on normal ``logs`` (files or folders of them) and write the model directory
    ``output`` where it judges anything (``options.keep_unskilled``: always). The result
    holds each signal's skill, the horizon and the predictor chosen: `auvdiag train`.
    ``options``: None for `TrainOptions()`."""
    from auvdiag_cli.audit.discovery import expand_logs
    from auvdiag_cli.jobs.train import DEFAULT_TRAINING, train_from_logs

    return train_from_logs(expand_logs(logs, progress), output, profile,
                           DEFAULT_TRAINING if options is None else options, progress)


def score(logs: Sequence[Path], profile: Profile, model: LoadedModel, *,
          horizon_s: float | None = None, progress: Progress = _quiet
          ) -> tuple[list[HorizonScore], HorizonScore]:
    """Measure the model's skill on normal logs it was not trained on, and record it in the
    model (write it with `save_model`); returns every horizon tried, with every signal's
    skill, and the one chosen: `auvdiag score`."""
    from auvdiag_cli.jobs.train import score_model

    return score_model(model, profile, logs, horizon_s, progress)


def relate(logs: Sequence[Path], profile: Profile, model: LoadedModel, *,
           holdout: Sequence[Path] = (), progress: Progress = _quiet
           ) -> tuple[CommandRelations | ThrustRelations | Refused, StartReference]:
    """Learn how the commands follow the motion and where normal logs start, into the model
    (write it with `save_model`): `auvdiag relate`. Returns both; a `Refused` relation or a
    start with ``refused`` set says why nothing was learned, and the model keeps what it
    had there."""
    from auvdiag_cli.jobs.relate import relate_model

    return relate_model(model, profile, logs, holdout, progress)


def calibrate(normal_logs: Sequence[Path], profile: Profile, model: LoadedModel, *,
              faulty_logs: Sequence[Path] = (), options: CalibrateOptions | None = None,
              progress: Progress = _quiet) -> CalibrationResult:
    """Set the model's thresholds from normal logs (files or folders of them), by
    ``options.margin`` x the largest g or to a false-alarm ``options.budget``; the model is
    updated (write it with `save_model`). ``faulty_logs`` are diagnosed with the new
    thresholds to show the margin: `auvdiag calibrate`. ``options``: None for
    `CalibrateOptions()`."""
    from auvdiag_cli.audit.discovery import expand_logs
    from auvdiag_cli.jobs.calibrate import DEFAULT_CALIBRATION
    from auvdiag_cli.jobs.calibrate import calibrate as set_thresholds

    return set_thresholds(model, profile, expand_logs(normal_logs, progress),
                          expand_logs(faulty_logs, progress),
                          DEFAULT_CALIBRATION if options is None else options,
                          progress)


def diagnose(path: Path, profile: Profile, model: LoadedModel, *,
             companions: Sequence[Path] = (), mission: Path | None = None,
             truth: Path | None = None) -> Diagnosis:
    """Diagnose one log. ``companions``: other logs of the same vehicle and day whose test
    sequences may decide between candidates; ``mission``: the mission plan for the
    closed-loop replay (default: NAME.mission.json beside the log); ``truth``: the log's
    ground truth (a simulator's NAME.truth.csv), to lay the substitution against."""
    from auvdiag_cli.engine.diagnosis import diagnose as diagnose_log
    from auvdiag_cli.jobs.truth import compare_with_truth

    diagnosis = diagnose_log(path, profile, model, companions, mission)
    return diagnosis if truth is None else compare_with_truth(diagnosis, profile, truth)


def to_json(diagnosis: Diagnosis) -> dict[str, Any]:
    """The JSON report (docs/reports.md, the JSON report) as a dict."""
    from auvdiag_cli.reports.json_report import diagnosis_to_dict

    return diagnosis_to_dict(diagnosis)


def build_report(diagnosis: Diagnosis) -> Report:
    """The typed report of a diagnosis: what the JSON report holds (``to_json`` of it is
    `to_json`), and what the summary, the PDF and the MCAP are drawn from."""
    from auvdiag_cli.reports.report_build import build_report as build

    return build(diagnosis)


def summary_text(diagnosis: Diagnosis) -> str:
    """The terminal summary `auvdiag diagnose` prints: verdict, onset and detection, each
    check's finding, notes (lines joined by newlines)."""
    from auvdiag_cli.reports.report_build import build_report as build
    from auvdiag_cli.reports.text import summary_lines

    return "\n".join(summary_lines(build(diagnosis)))


def write_reports(diagnosis: Diagnosis, *, json: Path | None = None, pdf: Path | None = None,
                  mcap: Path | None = None) -> None:
    """Write the diagnosis as a JSON report (with its time histories beside it, which
    `redraw_report` draws from), a PDF and an MCAP for Foxglove, as many as are asked."""
    from auvdiag_cli.reports.saved import write_diagnosis_files

    write_diagnosis_files(diagnosis, json, pdf, mcap)


def _reference(profile: Profile) -> Path:
    """How a worker process loads the same profile: its file, or its built-in name."""
    where = profile.source_path
    return Path(where.removeprefix("builtin:"))


def _refuse_unsaved(profile: Profile | None, model: LoadedModel | None) -> None:
    """An audit's workers read the profile from its file and the model from its directory:
    one changed in memory and not saved would be audited as it was on disk."""
    if profile is not None and load_profile(_reference(profile)) != profile:
        raise UsageError(f"audit: the profile differs from {profile.source_path}, which the "
                         "audit reads: save it to a file and load that")
    if model is None:
        return
    if model.directory is None:
        raise UsageError("audit needs a model read from a directory (api.load_model)")
    if model.unsaved:
        raise UsageError(f"audit: the model has changes not saved to {model.directory}, "
                         "which the audit reads: api.save_model it first")


def audit(paths: Sequence[Path | str], profile: Profile | None, model: LoadedModel | None,
          output: Path, *, jobs: int = 1, mcap: bool = False, scheduler: str | None = None,
          progress: AuditProgress | None = None, vehicle_from: str = "log") -> AuditResult:
    """Diagnose every log under ``paths`` (folders and globs) into ``output`` (one JSON
    report per log under logs/, audit.csv, audit.parquet and the fleet PDF audit.pdf),
    resuming a finished part. ``model``: a model read from a directory (None: the profile's
    shipped model); ``scheduler``: a Dask scheduler's address instead of ``jobs`` local
    processes; ``vehicle_from``: which vehicle of the fleet each log is (log, folder,
    regex:PATTERN or csv:FILE, as `auvdiag audit --vehicle-from`). The result holds an
    `AuditRecord` per log (``records``: verdict, component, fleet vehicle, worst margins…)
    and the counts; it is marked ``interrupted`` (with what finished saved) when the work is
    interrupted."""
    from auvdiag_cli.audit.fleet_pdf import render_fleet_report
    from auvdiag_cli.audit.job import AuditOptions, run_audit
    from auvdiag_cli.audit.progress import SilentReporter

    _refuse_unsaved(profile, model)
    options = AuditOptions([str(p) for p in paths], output,
                           None if profile is None else _reference(profile),
                           None if model is None or model.shipped else model.directory,
                           jobs, scheduler, mcap, vehicle_from)
    result = run_audit(options, progress or SilentReporter())
    render_fleet_report(result.records, result.skipped, output / "audit.pdf",
                        result.companions, result.interrupted)
    return result


def simulate(scenario: str | Scenario, profile: Profile, output: Path, *,
             log_format: str = "ros2-mcap", seed: int = 0, fault_at_s: float | None = None,
             start_ns: int | None = None, namespace: str = "") -> SimulatedDive:
    """Fly one of the profile's ``scenarios`` (by name, or a `Scenario` built from the
    simulator's steps) with its [simulation] physics and write it to
    ``output`` in ``log_format`` (bag, db3, ros2-mcap, mcap, tlog, bin, ulog, alog, csv) with
    its ground truth beside it (NAME.truth.json, NAME.truth.csv); an existing ``output``
    is never overwritten: `auvdiag simulate`. ``start_ns``: the log's first clock reading
    (None: 2026-11-22T10:00:00Z); ``namespace``: the ROS namespace the vehicle publishes
    under (ROS formats)."""
    from auvdiag_cli.simulator.run import LOG_EPOCH_NS
    from auvdiag_cli.simulator.run import simulate as fly
    from auvdiag_cli.simulator.scenarios import get_scenario
    from auvdiag_cli.simulator.writers import LOG_FORMATS, write_log

    if log_format not in LOG_FORMATS:
        raise UsageError(f"unknown log format {log_format!r} (choose from "
                         f"{', '.join(LOG_FORMATS)})")
    if output.exists():
        raise UsageError(f"{output}: exists already, not overwriting")
    # No such scenario, or a profile it cannot fly or log: the user's (no half log is kept).
    try:
        chosen = (get_scenario(scenario, profile, fault_at_s) if isinstance(scenario, str)
                  else scenario)
        dive = fly(chosen, profile, seed, LOG_EPOCH_NS if start_ns is None else start_ns)
        write_log(dive, profile, output, log_format, namespace=namespace)
    except (KeyError, ValueError) as error:
        raise UsageError(str(error).strip("'\"")) from None
    return dive


def scenarios(profile: Profile) -> dict[str, Scenario]:
    """The simulator's named scenarios for the profile's vehicle: `auvdiag scenarios`."""
    from auvdiag_cli.simulator.scenarios import scenarios_for

    return scenarios_for(profile)


def derive_table(log: Path | None, profile: Profile, model: LoadedModel) -> DerivedTable:
    """Every single-component fault simulated on the model, its b signatures and the pattern
    table they imply, compared with the profile's; with ``log`` (a normal log) the faults
    are replayed open loop on its commands: `auvdiag derive-table`."""
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.engine.signatures import derive_table as derive
    from auvdiag_cli.engine.signatures import log_mission

    open_loop = None if log is None else log_mission(ingest(log, profile).frame, profile)
    return derive(model, profile, open_loop=open_loop)


def trend(audit_dir: Path, *, last: int = 8, alpha: float = 0.05) -> FleetTrend:
    """Per vehicle and signal, whether the margin to the thresholds shrinks over the last
    ``last`` dives of an audit (Mann-Kendall at ``alpha``): `auvdiag trend`."""
    from auvdiag_cli.audit.trend import trend_of_audit

    return trend_of_audit(audit_dir, last, alpha)
