"""Audit progress: one plain line per log (CI logs, files), or nothing (a program using the
library). The live bar for a terminal is the command line's (`cli.progress_bar`)."""

import sys
from typing import Protocol

from auvdiag_cli.audit.record import AuditRecord


class Reporter(Protocol):
    def start(self, total: int, reused: int) -> None: ...

    def done(self, record: AuditRecord) -> None: ...

    def stop(self) -> None: ...


class PlainReporter:
    def __init__(self) -> None:
        self.total = self.count = 0

    def start(self, total: int, reused: int) -> None:
        self.total, self.count = total, reused
        print(f"auditing {total} logs ({reused} reused from an earlier run)", file=sys.stderr)

    def done(self, record: AuditRecord) -> None:
        self.count += 1
        print(f"[{self.count}/{self.total}] {record.log}: {record.describe()}",
              file=sys.stderr, flush=True)

    def stop(self) -> None:
        pass


class SilentReporter:
    def start(self, total: int, reused: int) -> None:
        pass

    def done(self, record: AuditRecord) -> None:
        pass

    def stop(self) -> None:
        pass

