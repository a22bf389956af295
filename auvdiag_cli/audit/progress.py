"""Audit progress: a live bar on a terminal (logs done, failed, time left), one plain line per
log otherwise (CI logs, files)."""

import sys
from typing import Any, Protocol

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)


class Reporter(Protocol):
    def start(self, total: int, reused: int) -> None: ...

    def done(self, record: dict[str, Any]) -> None: ...

    def stop(self) -> None: ...


def _describe(record: dict[str, Any]) -> str:
    if record.get("error"):
        return f"error: {record['error']}"
    what = record.get("component") or " or ".join(record.get("candidates") or [])
    return record.get("verdict", "?") + (f" ({what})" if what else "")


class PlainReporter:
    def __init__(self) -> None:
        self.total = self.count = 0

    def start(self, total: int, reused: int) -> None:
        self.total, self.count = total, reused
        print(f"auditing {total} logs ({reused} reused from an earlier run)", file=sys.stderr)

    def done(self, record: dict[str, Any]) -> None:
        self.count += 1
        print(f"[{self.count}/{self.total}] {record['log']}: {_describe(record)}",
              file=sys.stderr, flush=True)

    def stop(self) -> None:
        pass


class BarReporter:
    def __init__(self, console: Console) -> None:
        self.failed = 0
        self.progress = Progress(
            TextColumn("[bold]auditing"), BarColumn(), MofNCompleteColumn(),
            TextColumn("logs, [red]{task.fields[failed]} failed"), TimeElapsedColumn(),
            TextColumn("left"), TimeRemainingColumn(), console=console, transient=False)
        self.task = self.progress.add_task("audit", total=0, failed=0)

    def start(self, total: int, reused: int) -> None:
        self.progress.start()
        self.progress.update(self.task, total=total, completed=reused)

    def done(self, record: dict[str, Any]) -> None:
        self.failed += bool(record.get("error"))
        self.progress.update(self.task, advance=1, failed=self.failed)

    def stop(self) -> None:
        self.progress.stop()


def reporter_for_stderr() -> Reporter:
    console = Console(stderr=True)
    return BarReporter(console) if console.is_terminal else PlainReporter()

