"""The `auvdiag` command line: thin typer commands, one module per family, each calling one
function and printing what a report module formats."""

from auvdiag_cli.cli import dive, model, vehicle  # noqa: F401  (they register the commands)
from auvdiag_cli.cli.app import app, main

__all__ = ["app", "main"]
