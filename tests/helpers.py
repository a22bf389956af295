"""Helpers the test files share (the fixtures are in conftest)."""

import json
from pathlib import Path
from typing import Any

from typer.testing import CliRunner

from auvdiag_cli.cli import app


def diagnose_json(log: Path, *options: str) -> tuple[int, dict[str, Any]]:
    """`auvdiag diagnose LOG --json - --quiet OPTIONS`, as a user runs it: the exit status
    and the JSON report. A verdict must come out (exit status 0 or 1)."""
    result = CliRunner().invoke(app, ["diagnose", str(log), "--json", "-", "--quiet",
                                      *options])
    assert result.exit_code in (0, 1), result.output
    return result.exit_code, json.loads(result.stdout)
