"""The `auvdiag` command line: thin typer commands over the engine's functions."""

import json
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer

from auvdiag_cli import __version__
from auvdiag_cli.errors import UsageError

if TYPE_CHECKING:
    from auvdiag_cli.audit.job import AuditResult
    from auvdiag_cli.reports.series import Series

EXIT_NORMAL, EXIT_FAULT, EXIT_UNUSABLE = 0, 1, 2

app = typer.Typer(
    name="auvdiag",
    help="Diagnose autonomous underwater vehicles offline from their logs: replay the logged "
         "thruster commands through a learned model of the healthy vehicle, compare with the "
         "sensors, and say whether something broke, when, and which component "
         "(Takai & Ura, 1999).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="markdown",
)

ModelOption = Annotated[Path | None, typer.Option(
    "--model", help="Model directory (default: the model shipped for the profile's vehicle).",
    file_okay=False)]
ProfileOption = Annotated[Path | None, typer.Option(
    "--profile", help="Vehicle profile TOML, or a built-in one by name: twin_burger (the "
                      "default), three_thruster, bluerov2 (with DVL), bluerov2_standard, "
                      "bluerov2_heavy (no DVL), haizhe.",
    dir_okay=False)]

ModelToUpdateOption = Annotated[Path, typer.Option(
    "--model", help="Model directory to update.", file_okay=False, exists=True)]
CopyOutputOption = Annotated[Path | None, typer.Option(
    "--output", "-o", help="Write an updated copy of the model here instead of changing "
                           "--model.", file_okay=False)]
HorizonOption = Annotated[str | None, typer.Option(
    "--horizon", help="How long the model predicts before the replay re-starts from the "
                      "measured state: 'auto' (chosen on the held-out data), 'free' (the "
                      "paper's free run) or seconds. Default: the profile's [matching] "
                      "horizon_s, else auto.", metavar="auto|free|SECONDS")]


def _fail(message: str) -> NoReturn:
    from auvdiag_errors import one_line

    typer.echo(f"auvdiag: error: {one_line(message, 1000)}", err=True)
    raise typer.Exit(EXIT_UNUSABLE)


@contextmanager
def _user_errors(subject: Path | str) -> Iterator[None]:
    """Turn every failure into one line on stderr and exit status 2 (never a traceback)."""
    from auvdiag_cli.errors import AuvdiagError

    try:
        yield
    except (typer.Exit, BrokenPipeError):   # click quiets a reader that went away (| head)
        raise
    except AuvdiagError as error:
        _fail(str(error))
    except KeyboardInterrupt:
        _fail("interrupted")
    except Exception as error:
        if os.environ.get("AUVDIAG_DEBUG"):
            raise
        _fail(f"{subject}: unexpected {type(error).__name__}: {error} "
              "(set AUVDIAG_DEBUG=1 for the traceback)")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"auvdiag {__version__}")
        raise typer.Exit()


@app.callback()
def main_options(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="Print the version and exit.")] = False,
) -> None:
    """Offline model-based fault diagnosis for AUVs."""


@app.command()
def diagnose(
    log: Annotated[Path, typer.Argument(help="Log: ROS 1 .bag, ROS 2 bag directory (or its "
                                             ".db3/.mcap file), standalone .mcap, MAVLink "
                                             ".tlog, DataFlash .bin or CSV with a header "
                                             "row.")],
    model: ModelOption = None,
    profile: ProfileOption = None,
    json_path: Annotated[str | None, typer.Option(
        "--json", help="Write the JSON report to PATH, or to standard output with '-'. "
                       "Beside a JSON file go its time histories (NAME.series.npz), from "
                       "which 'auvdiag report' draws the PDF again.",
        metavar="PATH|-")] = None,
    pdf_path: Annotated[Path | None, typer.Option(
        "--pdf", help="Write the PDF report (summary page, time histories, Substituting "
                      "Control) to PATH.", dir_okay=False)] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No terminal summary.")] = False,
    mission: Annotated[Path | None, typer.Option(
        "--mission", help="Mission plan JSON for the closed-loop Substituting Control replay "
                          "(default: NAME.mission.json beside the log).", dir_okay=False)
    ] = None,
    companions: Annotated[list[Path] | None, typer.Option(
        "--with", help="Another log of the same vehicle and day whose Diagnosis Motion "
                       "Sequences may decide between candidates (repeatable).")] = None,
) -> None:
    """Diagnose one log. Exit status: 0 no fault, 1 fault found, 2 log not analysable.

    Segments come from the log's markers, or are recognised from the commands; each
    Diagnosis Motion Sequence is judged with its own thresholds, and when the pattern table
    leaves several candidates the DMS runs (in this log or the --with logs) decide."""
    from adapters import detect_format
    from auvdiag_cli.engine.diagnosis import Verdict
    from auvdiag_cli.engine.diagnosis import diagnose as run_diagnosis
    from auvdiag_cli.reports.json_report import diagnosis_to_dict
    from auvdiag_cli.reports.series import series_from_diagnosis
    from auvdiag_cli.reports.text import summary_lines
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    with _user_errors(log):
        detect_format(log)  # a bad path is reported before the model is even loaded
        vehicle = load_profile(profile)
        result = run_diagnosis(log, vehicle, load_model(model, vehicle.name), companions or (),
                               mission)
        document, series = diagnosis_to_dict(result), series_from_diagnosis(result)
        if json_path == "-":
            typer.echo(json.dumps(document, indent=2))
        elif json_path is not None:
            _save_report(document, series, Path(json_path))
        if pdf_path is not None:
            _render_pdf(document, series, pdf_path)
        if not quiet:
            for line in summary_lines(result):
                typer.echo(line, err=json_path == "-")
    raise typer.Exit(EXIT_FAULT if result.verdict == Verdict.FAULT else EXIT_NORMAL)


def _save_report(document: dict[str, Any], series: "Series", target: Path) -> None:
    """The JSON report and, beside it, the time histories it refers to."""
    from auvdiag_cli.files import write_json
    from auvdiag_cli.reports.series import save_series, series_path

    sidecar = series_path(target)
    save_series(series, sidecar)
    write_json({**document, "series_file": sidecar.name}, target)


def _render_pdf(document: dict[str, Any], series: "Series | None", target: Path) -> None:
    from auvdiag_cli.reports.pdf.dive import render_dive_report

    try:
        render_dive_report(document, series, target)
    except OSError as error:
        raise UsageError(f"{target}: cannot write the PDF: {error.strerror or error}") from None


@app.command()
def report(
    json_report: Annotated[Path, typer.Argument(help="A JSON report written by 'auvdiag "
                                                     "diagnose --json PATH' or by an audit.",
                                                dir_okay=False)],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="PDF to write (default: the JSON's name with .pdf).",
        dir_okay=False)] = None,
) -> None:
    """Draw the PDF report of a saved diagnosis, without the log or the model.

    The time histories come from the NAME.series.npz file written beside the JSON; without
    it the report has its summary pages only."""
    from auvdiag_cli.reports.series import load_series

    with _user_errors(json_report):
        document = _read_report(json_report)
        named = document.get("series_file")
        sidecar = json_report.with_name(named) if isinstance(named, str) and named else None
        series = load_series(sidecar) if sidecar is not None and sidecar.is_file() else None
        if series is None:
            typer.echo(f"auvdiag: note: {json_report}: no time histories beside it; the PDF "
                       "has its summary pages only", err=True)
        target = output or json_report.with_suffix(".pdf")
        try:
            _render_pdf(document, series, target)
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as error:
            # The document came from a file: a field missing or of the wrong kind is the
            # file's problem, not a bug (reports this version writes are drawn in tests).
            raise UsageError(f"{json_report}: not a complete auvdiag report "
                             f"({type(error).__name__}: {error})") from None
        typer.echo(f"report written to {target}")


def _read_report(path: Path) -> dict[str, Any]:
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise UsageError(f"{path}: not a readable JSON report: {error}") from None
    if not isinstance(document, dict) or "verdict" not in document or "log" not in document:
        raise UsageError(f"{path}: not an auvdiag JSON report (no 'verdict' or 'log')")
    return document


class FailOn(StrEnum):
    """What makes an audit's exit status non-zero."""

    ANY = "any"
    DAMAGED = "damaged"
    FAULT = "fault"
    ERROR = "error"
    NONE = "none"


def _audit_exit(result: "AuditResult", fail_on: FailOn) -> int:
    counted = {FailOn.ANY: ("fault", "error"), FailOn.DAMAGED: ("fault", "error", "damaged"),
               FailOn.FAULT: ("fault",), FailOn.ERROR: ("error",), FailOn.NONE: ()}[fail_on]
    if "error" in counted and result.errors:
        return EXIT_UNUSABLE
    if "damaged" in counted and result.damaged:
        return EXIT_UNUSABLE
    if "fault" in counted and result.count("fault"):
        return EXIT_FAULT
    return EXIT_NORMAL


def _terminate_as_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


@app.command()
def audit(
    paths: Annotated[list[str], typer.Argument(
        help="Logs, folders (walked for logs of every format) or glob patterns.")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Folder for the results.",
                                         file_okay=False)],
    model: ModelOption = None,
    profile: ProfileOption = None,
    jobs: Annotated[int, typer.Option(
        "--jobs", "-j", help="Logs diagnosed side by side (default: all cores).", min=1)
    ] = os.cpu_count() or 1,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", help="Address of a Dask scheduler (e.g. tcp://host:8786) to run on "
                            "instead of local processes; needs the 'dask' extra, and the "
                            "workers need the logs at the same paths.")] = None,
    fail_on: Annotated[FailOn, typer.Option(
        "--fail-on", help="What makes the exit status non-zero: any (faults: 1, logs not "
                          "analysable: 2), damaged (as any, and a log analysed only up to "
                          "damage also gives 2), fault, error, or none.")] = FailOn.ANY,
) -> None:
    """Diagnose every log under PATHS and write one table and a fleet summary.

    Writes OUTPUT/audit.csv and OUTPUT/audit.parquet (a row per log; a log that cannot be
    analysed is a row with its error), OUTPUT/audit.pdf, and OUTPUT/logs/ with each log's
    JSON report. Results are saved as each log finishes: an interrupted audit loses nothing
    finished, and running it again only diagnoses what is missing or whose log or model
    changed. Exit status: 0 all normal, 1 a fault found, 2 a log not analysable."""
    import signal

    from auvdiag_cli.audit.fleet_pdf import render_fleet_report
    from auvdiag_cli.audit.job import AuditOptions, run_audit
    from auvdiag_cli.audit.progress import reporter_for_stderr

    signal.signal(signal.SIGTERM, _terminate_as_interrupt)
    options = AuditOptions(paths, output, profile, model, jobs, scheduler)
    with _user_errors(output):
        result = run_audit(options, reporter_for_stderr())
        render_fleet_report(result.records, result.skipped, output / "audit.pdf",
                            result.companions, result.interrupted)
    typer.echo(f"{len(result.records)} logs: {result.count('normal')} normal, "
               f"{result.count('fault')} fault, {result.count('undetermined')} undetermined, "
               f"{result.errors} not analysable, {result.damaged} partial (damaged); "
               f"{len(result.skipped)} files skipped; "
               f"{result.computed} diagnosed now, {result.reused} reused; results in {output}")
    if result.interrupted:
        _fail(f"audit interrupted after {result.computed} logs; run it again to finish")
    raise typer.Exit(_audit_exit(result, fail_on))


def _horizon_option(text: str | None, profile_default: float | None) -> float | None:
    """--horizon as the trainer takes it: None chooses, inf is the paper's free run; no
    option keeps the profile's ``[matching] horizon_s``."""
    import math

    if text is None:
        return profile_default
    if text == "auto":
        return None
    if text == "free":
        return math.inf
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 < value < math.inf:
        raise UsageError(f"--horizon must be 'auto', 'free' or a positive number of seconds, "
                         f"got {text!r}")
    return value


@app.command()
def train(
    logs: Annotated[list[Path], typer.Argument(help="Normal-condition logs to learn from.")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Model directory to write.",
                                         file_okay=False)],
    profile: ProfileOption = None,
    holdout: Annotated[list[Path] | None, typer.Option(
        "--holdout", help="Held-out normal log for the skill figures (repeatable; default: "
                          "every fifth log, or the last 20 % of a single log).")] = None,
    horizon: HorizonOption = None,
    keep_unskilled: Annotated[bool, typer.Option(
        "--keep-unskilled", help="Write the model even when no signal has skill (its "
                                 "diagnoses will judge nothing).")] = False,
    hidden: Annotated[int, typer.Option(help="Size of the recurrent context.", min=4)] = 32,
    seed: Annotated[int, typer.Option(help="Random seed of the training.")] = 0,
    iterations_scale: Annotated[float, typer.Option(
        help="Multiply every stage's iteration count (e.g. 0.1 for a quick model).",
        min=0.001)] = 1.0,
) -> None:
    """Train the healthy-vehicle dynamics model on normal logs and write a model directory.

    Training runs in stages, short rollouts first and long free-running ones after. The
    model is then scored on held-out normal data against naive predictors (the last value
    holds, the mean, a linear model): a signal it cannot predict better is never judged.
    It also learns how the commands follow the motion (see 'auvdiag relate'). Exit status 1
    when nothing can be judged (no model is written unless --keep-unskilled)."""
    from auvdiag_cli.jobs.train import paper_model_error, train_from_logs
    from auvdiag_cli.reports.training import training_lines
    from auvdiag_cli.vehicle.profile import load_profile

    with _user_errors(output):
        vehicle = load_profile(profile)
        result = train_from_logs(logs, output, vehicle, holdout or (), hidden, seed,
                                 iterations_scale, _horizon_option(horizon, vehicle.horizon_s),
                                 keep_unskilled,
                                 progress=_progress)
    for line in training_lines(result, paper_model_error(vehicle), vehicle.command_names,
                               vehicle.sensor_names):
        typer.echo(line)
    if not result.judges_anything:
        typer.echo("auvdiag: no signal has skill, or enough held-out data to show it, and no "
                   "actuator's commands can be judged (see above)"
                   + ("" if result.written else "; the model is not written (--keep-unskilled "
                                                "writes it anyway)"), err=True)
        raise typer.Exit(EXIT_FAULT)


@app.command()
def score(
    logs: Annotated[list[Path], typer.Argument(help="Normal logs the model was not trained on.")],
    model: ModelToUpdateOption,
    horizon: HorizonOption = None,
    output: CopyOutputOption = None,
    profile: ProfileOption = None,
) -> None:
    """Measure an existing model's skill per signal on normal logs and record it.

    For models trained before skill was measured, or to re-check a model on new dives: the
    skill and prediction horizon found replace those in model.json, and signals without
    skill are no longer judged. Exit status 1 when no signal has skill."""
    from auvdiag_cli.jobs.calibrate import write_metadata
    from auvdiag_cli.jobs.train import score_model
    from auvdiag_cli.reports.training import skill_lines
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    with _user_errors(model):
        vehicle = load_profile(profile)
        loaded = load_model(model)
        scores, chosen = score_model(loaded, vehicle, logs,
                                     _horizon_option(horizon, vehicle.horizon_s), _progress)
        write_metadata(loaded, output or model)
    for line in skill_lines(scores, chosen):
        typer.echo(line)
    typer.echo(f"skill written to {(output or model) / 'model.json'}")
    if not chosen.judged:
        raise typer.Exit(EXIT_FAULT)


@app.command()
def relate(
    logs: Annotated[list[Path], typer.Argument(help="Normal logs to learn from.")],
    model: ModelToUpdateOption,
    holdout: Annotated[list[Path] | None, typer.Option(
        "--holdout", help="Held-out normal log that sets the thresholds (repeatable; "
                          "default: every fifth log, or the last 20 % of a single log).")
    ] = None,
    output: CopyOutputOption = None,
    profile: ProfileOption = None,
) -> None:
    """Learn how the vehicle's commands follow its motion, and where its logs start.

    A controller holding heading, depth or attitude hides a weakened thruster from the
    motion by driving it harder; the commands then depart from what the motion needs. This
    learns that relation from normal logs (DMS runs and open-loop logs are left out) and
    sets, per actuator, how much extra effort normal logs reach. It also records where the
    normal logs recorded from rest start, so that a sensor wrong from the first sample is
    found. 'auvdiag train' does both itself; use this command for a model trained before,
    or to learn from other dives. What cannot be learned keeps what the model had."""
    from auvdiag_cli.jobs.calibrate import write_metadata
    from auvdiag_cli.jobs.relate import relate_model
    from auvdiag_cli.reports.training import relation_lines, start_lines
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    with _user_errors(model):
        vehicle = load_profile(profile)
        loaded = load_model(model)
        relations, start = relate_model(loaded, vehicle, logs, holdout or (), _progress)
        if "refused" not in relations or "refused" not in start:
            write_metadata(loaded, output or model)
    for line in [*relation_lines(relations, vehicle.command_names),
                 *start_lines(start, vehicle.sensor_names)]:
        typer.echo(line)
    if "refused" in relations and "refused" in start:
        typer.echo("auvdiag: nothing learned; the model is left as it was", err=True)
        raise typer.Exit(EXIT_FAULT)
    typer.echo(f"written to {(output or model) / 'model.json'}")
    if "refused" in relations:
        raise typer.Exit(EXIT_FAULT)


@app.command()
def calibrate(
    logs: Annotated[list[Path], typer.Argument(help="Normal-condition logs.")],
    model: ModelToUpdateOption,
    faulty: Annotated[list[Path] | None, typer.Option(
        "--faulty", help="A log with a known fault, to check detection (repeatable).")
    ] = None,
    margin: Annotated[float, typer.Option(help="Threshold = margin x largest normal g.")
                      ] = 1.5,
    output: CopyOutputOption = None,
    profile: ProfileOption = None,
    floor_at_profile: Annotated[bool, typer.Option(
        "--floor-at-profile", help="Never set a threshold below the profile's for its mode "
                                   "(for few calibration logs, or signals a DMS hardly moves)."
    )] = False,
) -> None:
    """Set the model's thresholds from the g it reaches on normal logs.

    Per diagnosis mode (mission, ZA, ZB, ZC) and signal: threshold = margin x the largest g
    on the normal logs (zero false alarms there by construction; the implied rate is stated
    as a 95 % upper bound). Modes with under 30 s of data keep the profile's
    thresholds, raised where these logs need it.
    With --faulty, those logs are diagnosed with the new thresholds to show the margin."""
    from auvdiag_cli.jobs.calibrate import calibrate as run_calibration
    from auvdiag_cli.jobs.calibrate import write_metadata
    from auvdiag_cli.reports.training import calibration_lines
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    with _user_errors(model):
        loaded = load_model(model)
        result = run_calibration(loaded, load_profile(profile), logs, faulty or (), margin,
                                 floor_at_profile)
        write_metadata(loaded, output or model)
    for line in calibration_lines(result):
        typer.echo(line)
    typer.echo(f"thresholds written to {(output or model) / 'model.json'}")


def _progress(message: str) -> None:
    typer.echo(message, err=True)


@app.command()
def simulate(
    scenario: Annotated[str, typer.Argument(help="Scenario name (see 'auvdiag scenarios').")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Log path to write.")],
    log_format: Annotated[str, typer.Option(
        "--format", help="Log format: bag (ROS 1), db3 (ROS 2, sqlite3), ros2-mcap (ROS 2, "
                         "mcap storage), mcap (standalone), tlog (MAVLink), bin (DataFlash), "
                         "csv (the profile's [sources.csv] columns)."
    )] = "ros2-mcap",
    seed: Annotated[int, typer.Option(help="Noise seed.")] = 0,
    fault_at: Annotated[float | None, typer.Option(
        help="Move the scenario's fault onset to this time (s).")] = None,
    start: Annotated[str, typer.Option(
        help="When the log's clock starts (ISO 8601, UTC if no zone).")
    ] = "2026-11-22T10:00:00Z",
    profile: ProfileOption = None,
) -> None:
    """Simulate a dive of the profile's vehicle and write it as a log with its ground truth.

    The vehicle is flown with the physics of the profile's [simulation] table and logged the
    way its [sources] tables describe. The truth goes to NAME.truth.json (scenario, fault,
    onset) and NAME.truth.csv (true velocities, heading, position and depth at 10 Hz); a
    mission's plan to NAME.mission.json."""
    from auvdiag_cli.simulator.run import simulate as run_simulation
    from auvdiag_cli.simulator.scenarios import get_scenario
    from auvdiag_cli.simulator.writers import LOG_FORMATS, truth_paths, write_log
    from auvdiag_cli.vehicle.profile import load_profile

    if log_format not in LOG_FORMATS:
        _fail(f"unknown --format {log_format!r} (choose from {', '.join(LOG_FORMATS)})")
    with _user_errors(output):
        vehicle = load_profile(profile)
        try:
            chosen = get_scenario(scenario, vehicle, fault_at)
            if output.exists():
                _fail(f"{output}: exists already, not overwriting")
            dive = run_simulation(chosen, vehicle, seed, _unix_ns(start))
            write_log(dive, vehicle, output, log_format)
        except (KeyError, ValueError) as error:
            _fail(str(error).strip("'\""))
    typer.echo(f"wrote {output} ({log_format}, {dive.duration_s:.1f} s) and "
               f"{truth_paths(output)[0].name}")


@app.command()
def inspect(
    log: Annotated[Path, typer.Argument(help="Log of any supported format.")],
    profile: ProfileOption = None,
) -> None:
    """Show what a log holds and which of the profile's signals resolve in it.

    Lists the format, time span, topics or message types with their types, counts and rates,
    and for each profile signal whether it resolved (or why not, with the closest topics).
    Exit status 0 when every signal resolves, 2 otherwise (also when the log holds none of
    them, or the profile has no mapping for its format: the listing still shows what the
    log holds)."""
    from auvdiag_cli.jobs.inspect import inspect_log
    from auvdiag_cli.reports.text import inspection_lines
    from auvdiag_cli.vehicle.profile import load_profile

    with _user_errors(log):
        result = inspect_log(log, load_profile(profile))
    for line in inspection_lines(result):
        typer.echo(line)
    if not result.usable:
        raise typer.Exit(EXIT_UNUSABLE)


def _unix_ns(text: str) -> int:
    from datetime import UTC, datetime

    try:
        moment = datetime.fromisoformat(text)
    except ValueError:
        _fail(f"--start {text!r} is not an ISO 8601 time (e.g. 2026-11-22T10:00:00Z)")
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=UTC)
    return round(moment.timestamp() * 1e9)


@app.command("init-profile")
def init_profile(
    log: Annotated[Path, typer.Argument(help="A log of the vehicle, of any supported format.")],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Profile file to write (default: print it).", dir_okay=False)
    ] = None,
    name: Annotated[str | None, typer.Option(
        help="The vehicle's name (default: the log's name).")] = None,
    like: Annotated[Path | None, typer.Option(
        "--like", help="Start from this profile (a file, or a built-in one such as "
                       "bluerov2_standard) and fit its mapping to the log.", dir_okay=False)
    ] = None,
) -> None:
    """Write a starting vehicle profile from what a log holds.

    Proposes as commands the motor outputs, thrust or PWM fields and as sensors the gyro
    rates, climb or depth rates and velocities that are in the log and vary there, the
    log's armed flag as operating time, and for CSV the clock column. What a log cannot
    tell (units, full scales, components, thresholds, the pattern table) is marked CHECK.
    With --like, the draft is that profile with each signal that does not read on the log
    moved to the closest field that does (each move listed at the top). The draft loads and
    resolves on the log it came from: `auvdiag inspect LOG --profile FILE` shows it."""
    from adapters import detect_format
    from auvdiag_cli.jobs.profile_draft import draft_profile
    from auvdiag_cli.jobs.profile_like import draft_like

    with _user_errors(log):
        detect_format(log)
        text = draft_profile(log, name or log.stem) if like is None else draft_like(log, like)
        if output is None:
            typer.echo(text, nl=False)
            return
        if output.exists():
            raise UsageError(f"{output}: exists already, not overwriting")
        output.write_text(text, encoding="utf-8")
    typer.echo(f"profile written to {output}; check the lines marked CHECK, then: auvdiag "
               f"inspect {log} --profile {output}")


@app.command("derive-table")
def derive_table(
    model: ModelOption = None,
    profile: ProfileOption = None,
    json_path: Annotated[Path | None, typer.Option(
        "--json", help="Also write the signatures and the table as JSON.", dir_okay=False)
    ] = None,
    log: Annotated[Path | None, typer.Option(
        "--log", help="A normal log of the vehicle: the faults are replayed open loop on its "
                      "commands instead of on a mission flown by the profile's controller.")
    ] = None,
) -> None:
    """Derive the pattern table by simulating every single-component fault on the model.

    Each thruster producing nothing and each sensor reading zero is simulated with the
    dynamics model as the vehicle, on every DMS and on a mission: flown by the profile's
    controller, or open loop on the commands of --log, or (a profile without a controller
    and no --log) on the DMSs played one after another. The b signatures are printed, and
    the table they imply is compared with the profile's. Exit status 0 when they agree, 1
    when they differ."""
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.engine.signatures import derive_table as run_derivation
    from auvdiag_cli.engine.signatures import log_mission
    from auvdiag_cli.files import write_json
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    with _user_errors(log or model or "builtin model"):
        loaded_profile = load_profile(profile)
        open_loop = (None if log is None
                     else log_mission(ingest(log, loaded_profile).frame, loaded_profile))
        result = run_derivation(load_model(model, loaded_profile.name), loaded_profile,
                                open_loop=open_loop)
    names = loaded_profile.sensor_names
    modes = list(result.signatures[0].b)
    typer.echo("b signatures (" + ", ".join(names) + ") of each single fault:")
    typer.echo(f"  {'component':<18}" + "".join(f"{mode:>10}" for mode in modes))
    for signature in result.signatures:
        cells = ["".join(str(signature.b[mode][n]) for n in names) for mode in modes]
        typer.echo(f"  {signature.component:<18}" + "".join(f"{c:>10}" for c in cells))
    typer.echo("pattern table derived from the mission signatures:")
    for row in result.rows:
        bits = ", ".join(f"{n}={row.b[n]}" for n in names)
        typer.echo(f"  case {row.case}: {bits}  ->  "
                   + (" or ".join(row.components) or "nothing"))
    if result.unseen_on_mission:
        typer.echo("  not seen on the mission (only on the DMSs above): "
                   + ", ".join(result.unseen_on_mission))
    typer.echo("matches the profile's table" if result.matches_profile
               else "DIFFERS from the profile's table")
    if json_path is not None:
        write_json({"signatures": [s.__dict__ for s in result.signatures],
                    "table": [r.__dict__ for r in result.rows],
                    "matches_profile": result.matches_profile}, json_path)
    raise typer.Exit(EXIT_NORMAL if result.matches_profile else EXIT_FAULT)


@app.command()
def scenarios(profile: ProfileOption = None) -> None:
    """List the simulator's named scenarios for the profile's vehicle."""
    from auvdiag_cli.simulator.scenarios import scenarios_for
    from auvdiag_cli.vehicle.profile import load_profile

    with _user_errors(profile or "builtin profile"):
        known = scenarios_for(load_profile(profile))
    width = max(len(name) for name in known)
    for name, scenario in known.items():
        typer.echo(f"{name:<{width}}  {scenario.description}")


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    command: Callable[..., object] = app
    command(args=argv if argv is not None else sys.argv[1:], prog_name="auvdiag")
