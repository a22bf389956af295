"""Python's bytecode cache for this project, written before a benchmark times anything. An
installed copy has it (pip compiles on install, and a first run writes it), but a shell with
PYTHONDONTWRITEBYTECODE set never writes it: every process of a benchmark would compile the
project's sources afresh, about 0.1 s a process that no user pays."""

import compileall
from pathlib import Path

PACKAGES = ("adapters", "auvdiag_cli", "auvdiag_errors", "models")


def write_bytecode() -> None:
    root = Path(__file__).resolve().parents[1]
    for package in PACKAGES:
        compileall.compile_dir(root / package, quiet=1)
