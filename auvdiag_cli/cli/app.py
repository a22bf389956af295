"""The `auvdiag` application: the typer app, the options several commands share, and the
one rule for failures (one line on stderr, exit status 2)."""

import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NoReturn

import typer

from auvdiag_cli import __version__
from auvdiag_cli.vehicle.profile import builtin_profiles
from auvdiag_errors import UsageError

if TYPE_CHECKING:
    pass

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
_PROFILES = ("Vehicle profile TOML, or a built-in one by name: "
             + ", ".join(f"{name} (the default)" if name == "twin_burger" else name
                         for name in builtin_profiles()) + ".")
ProfileOption = Annotated[Path | None, typer.Option(
    "--profile", help=_PROFILES, dir_okay=False)]
# Where a model is given, the profile it was trained with is the one its logs are read by.
ModelProfileOption = Annotated[Path | None, typer.Option(
    "--profile", help=_PROFILES.replace("(the default)", "(the default without --model)")
    + " Default with --model: the profile the model was trained with.", dir_okay=False)]

ModelToUpdateOption = Annotated[Path, typer.Option(
    "--model", help="Model directory to update.", file_okay=False, exists=True)]
CopyOutputOption = Annotated[Path | None, typer.Option(
    "--output", "-o", help="Write an updated copy of the model here instead of changing "
                           "--model.", file_okay=False)]
HoldoutOption = Annotated[list[Path] | None, typer.Option(
    "--holdout", help="Held-out normal log: the skill figures and the command relations' and "
                      "start's allowances are measured on it (repeatable; default: every "
                      "fifth log, or the last 20 % of a single log).")]
HealthyOption = Annotated[Path | None, typer.Option(
    "--healthy", metavar="FILE", exists=True, dir_okay=False,
    help="A CSV with columns log,start,end: use only that part of each listed log (its path "
         "or name as given; times on the log's own clock as 'auvdiag inspect' prints its "
         "span, in seconds or ISO 8601; empty: from its start / to its end). Logs not listed "
         "are used whole: a flight that failed late still gives its healthy beginning.")]
HorizonOption = Annotated[str | None, typer.Option(
    "--horizon", help="How long the model predicts before the replay re-starts from the "
                      "measured state: 'auto' (chosen on the held-out data), 'free' (the "
                      "paper's free run) or seconds. Default: the profile's [matching] "
                      "horizon_s, else auto.", metavar="auto|free|SECONDS")]


def fail(message: str) -> NoReturn:
    from auvdiag_errors import one_line

    typer.echo(f"auvdiag: error: {one_line(message, 1000)}", err=True)
    raise typer.Exit(EXIT_UNUSABLE)


@contextmanager
def user_errors(subject: Path | str) -> Iterator[None]:
    """Turn every failure into one line on stderr and exit status 2 (never a traceback)."""
    from auvdiag_errors import AuvdiagError

    try:
        yield
    except (typer.Exit, BrokenPipeError):   # click quiets a reader that went away (| head)
        raise
    except AuvdiagError as error:
        fail(str(error))
    except KeyboardInterrupt:
        fail("interrupted")
    except Exception as error:
        if os.environ.get("AUVDIAG_DEBUG"):
            raise
        fail(f"{subject}: unexpected {type(error).__name__}: {error} "
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


def report_progress(message: str) -> None:
    typer.echo(message, err=True)


def log_paths(paths: list[Path]) -> list[Path]:
    """The logs given, a folder standing for every log under it (a ROS 2 bag folder is
    one log); what a folder holds that is not a log is named on stderr."""
    from auvdiag_cli.audit.discovery import expand_logs

    return expand_logs(paths, report_progress)


def horizon_option(text: str | None, profile_default: float | None) -> float | None:
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


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    command: Callable[..., object] = app
    command(args=argv if argv is not None else sys.argv[1:], prog_name="auvdiag")
