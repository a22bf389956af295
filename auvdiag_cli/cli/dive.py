"""`diagnose`, `report` and `audit`: one log, a saved report, a fleet."""

import json
import os
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from auvdiag_cli.cli.app import (
    EXIT_FAULT,
    EXIT_NORMAL,
    EXIT_UNUSABLE,
    ModelOption,
    ModelProfileOption,
    app,
    fail,
    user_errors,
)

if TYPE_CHECKING:
    from auvdiag_cli.audit.job import AuditResult


@app.command()
def diagnose(
    log: Annotated[Path, typer.Argument(help="Log: ROS 1 .bag, ROS 2 bag directory (or its "
                                             ".db3/.mcap file), standalone .mcap, MAVLink "
                                             ".tlog, DataFlash .bin, PX4 ULog .ulg, MOOS-IvP "
                                             ".alog or CSV with a header row.")],
    model: ModelOption = None,
    profile: ModelProfileOption = None,
    json_path: Annotated[str | None, typer.Option(
        "--json", help="Write the JSON report to PATH, or to standard output with '-'. "
                       "Beside a JSON file go its time histories (NAME.series.npz), from "
                       "which 'auvdiag report' draws the PDF again.",
        metavar="PATH|-")] = None,
    pdf_path: Annotated[Path | None, typer.Option(
        "--pdf", help="Write the PDF report (summary page, time histories, Substituting "
                      "Control) to PATH.", dir_okay=False)] = None,
    mcap_path: Annotated[Path | None, typer.Option(
        "--mcap", help="Write the diagnosis as an MCAP file (sensor, model, g, threshold, b "
                       "per signal; commands; segments; onset, detection and verdict as "
                       "events) on the log's own clock, to open beside the log in Foxglove "
                       "or PlotJuggler.", dir_okay=False)] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No terminal summary.")] = False,
    mission: Annotated[Path | None, typer.Option(
        "--mission", help="Mission plan JSON for the closed-loop Substituting Control replay "
                          "(default: NAME.mission.json beside the log).", dir_okay=False)
    ] = None,
    companions: Annotated[list[Path] | None, typer.Option(
        "--with", help="Another log of the same vehicle and day whose Diagnosis Motion "
                       "Sequences may decide between candidates (repeatable).")] = None,
    truth: Annotated[Path | None, typer.Option(
        "--truth", help="The log's ground truth (CSV with a t_s column and true values, as "
                        "`auvdiag simulate` writes NAME.truth.csv): the substituted signal "
                        "and the failed sensor are laid against it.", dir_okay=False)
    ] = None,
) -> None:
    """Diagnose one log. Exit status: 0 no fault, 1 fault found, 2 log not analysable.

    Segments come from the log's markers, or are recognised from the commands; each
    Diagnosis Motion Sequence is judged with its own thresholds, and when the pattern table
    leaves several candidates the DMS runs (in this log or the --with logs) decide."""
    from auvdiag_cli import api
    from auvdiag_cli.jobs.profile_fit import with_profile_hint
    from auvdiag_errors import LogError

    with user_errors(log):
        api.log_format(log)   # a bad path is reported before the model is even loaded
        vehicle = api.load_profile(profile, model=model)
        try:
            result = api.diagnose(log, vehicle, api.load_model(model, vehicle),
                                  companions=companions or (), mission=mission, truth=truth)
        except LogError as error:
            raise with_profile_hint(error, vehicle.name) from None
        if json_path == "-":
            typer.echo(json.dumps(api.to_json(result), indent=2))
        api.write_reports(result, json=None if json_path in (None, "-") else Path(json_path),
                          pdf=pdf_path, mcap=mcap_path)
        if not quiet:
            typer.echo(api.summary_text(result), err=json_path == "-")
    raise typer.Exit(EXIT_FAULT if result.verdict == api.Verdict.FAULT else EXIT_NORMAL)


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
    from auvdiag_cli import api

    target = output or json_report.with_suffix(".pdf")
    with user_errors(json_report):
        if not api.redraw_report(json_report, target):
            typer.echo(f"auvdiag: note: {json_report}: no time histories beside it; the PDF "
                       "has its summary pages only", err=True)
    typer.echo(f"report written to {target}")


class FailOn(StrEnum):
    """What makes an audit's exit status non-zero."""

    ANY = "any"
    DAMAGED = "damaged"
    PARTIAL = "partial"
    FAULT = "fault"
    ERROR = "error"
    NONE = "none"


def _audit_exit(result: "AuditResult", fail_on: FailOn) -> int:
    counted = {FailOn.ANY: ("fault", "error"), FailOn.DAMAGED: ("fault", "error", "damaged"),
               FailOn.PARTIAL: ("fault", "error", "partial"), FailOn.FAULT: ("fault",),
               FailOn.ERROR: ("error",), FailOn.NONE: ()}[fail_on]
    if "error" in counted and result.errors:
        return EXIT_UNUSABLE
    if "damaged" in counted and result.damaged:
        return EXIT_UNUSABLE
    if "fault" in counted and result.count("fault"):
        return EXIT_FAULT
    if "partial" in counted and (result.partly_judged or result.count("undetermined")):
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
    profile: ModelProfileOption = None,
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
                          "damage also gives 2), partial (as any, and a NORMAL that judged "
                          "less than every signal and actuator, or an UNDETERMINED, also "
                          "gives 1), fault, error, or none.")] = FailOn.ANY,
    mcap: Annotated[bool, typer.Option(
        "--mcap", help="Also write each log's diagnosis as an MCAP (OUTPUT/logs/NAME.mcap) "
                       "to open beside the log in Foxglove or PlotJuggler.")] = False,
    vehicle_from: Annotated[str, typer.Option(
        "--vehicle-from", metavar="log|folder|regex:PATTERN|csv:FILE",
        help="Which vehicle of the fleet each log is, for the trend and the fleet PDF: log "
             "(the default: the id the log gives, a MAVLink system id other than the default "
             "1 or the board's unique id, a ULog's sys_uuid or sys_name, the ROS namespace "
             "of its topics, else the folder), folder, regex:PATTERN (its first "
             "group in the file name, else the folder) or csv:FILE (rows 'log,vehicle').")
    ] = "log",
) -> None:
    """Diagnose every log under PATHS and write one table and a fleet summary.

    Writes OUTPUT/audit.csv and OUTPUT/audit.parquet (a row per log; a log that cannot be
    analysed is a row with its error), OUTPUT/audit.pdf, and OUTPUT/logs/ with each log's
    JSON report. Results are saved as each log finishes: an interrupted audit loses nothing
    finished, and running it again only diagnoses what is missing or whose log or model
    changed. Exit status: 0 all normal, 1 a fault found, 2 a log not analysable."""
    import signal

    from auvdiag_cli import api
    from auvdiag_cli.cli.progress_bar import reporter_for_stderr

    signal.signal(signal.SIGTERM, _terminate_as_interrupt)
    with user_errors(output):
        vehicle = api.load_profile(profile, model=model)
        result = api.audit(paths, vehicle, api.load_model(model, vehicle), output, jobs=jobs,
                           mcap=mcap, scheduler=scheduler, progress=reporter_for_stderr(),
                           vehicle_from=vehicle_from)
    typer.echo(result.summary(output))
    if result.interrupted:
        fail(f"audit interrupted after {result.computed} logs; run it again to finish")
    raise typer.Exit(_audit_exit(result, fail_on))


@app.command()
def trend(
    audit_dir: Annotated[Path, typer.Argument(help="An audit's output folder (its logs/ "
                                                   "holds the per-log reports).",
                                              file_okay=False)],
    last: Annotated[int, typer.Option("--last", help="Dives per vehicle the test looks at "
                                                     "(the most recent).", min=3)] = 8,
    alpha: Annotated[float, typer.Option("--alpha", help="Significance of the trend test.",
                                         min=0.0001, max=0.5)] = 0.05,
) -> None:
    """Fleet health over time: flag vehicles whose margin to the thresholds is shrinking.

    Per vehicle (as the audit's --vehicle-from assigned it) and per signal, the peak ratio
    to the threshold of each dive, in the dives' date order; Mann-Kendall's rank test over
    the last dives flags a rising ratio that has not alarmed yet. Exit status 1 when a vehicle is
    flagged, 0 otherwise."""
    from auvdiag_cli import api
    from auvdiag_cli.audit.trend import trend_lines

    with user_errors(audit_dir):
        result = api.trend(audit_dir, last=last, alpha=alpha)
    for line in trend_lines(result):
        typer.echo(line)
    raise typer.Exit(EXIT_FAULT if result.flagged else EXIT_NORMAL)
