"""Audit progress: one plain line per log (CI logs, files), or nothing (a program using the
library). The live bar for a terminal is the command line's (`cli.progress_bar`)."""

import sys
from typing import Any, Protocol


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


class SilentReporter:
    def start(self, total: int, reused: int) -> None:
        pass

    def done(self, record: dict[str, Any]) -> None:
        pass

    def stop(self) -> None:
        pass

