"""The audit's live bar on a terminal (logs done, failed, time left); plain lines elsewhere."""

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from auvdiag_cli.audit.progress import PlainReporter, Reporter
from auvdiag_cli.audit.record import AuditRecord


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

    def done(self, record: AuditRecord) -> None:
        self.failed += bool(record.error)
        self.progress.update(self.task, advance=1, failed=self.failed)

    def stop(self) -> None:
        self.progress.stop()


def reporter_for_stderr() -> Reporter:
    console = Console(stderr=True)
    return BarReporter(console) if console.is_terminal else PlainReporter()
