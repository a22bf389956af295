"""The healthy parts of logs to learn from (`train --healthy`, `calibrate --healthy`): a CSV
with the columns ``log,start,end``, one row per log. ``log`` is the log's path or name as
given on the command line; ``start`` and ``end`` are times on the log's own clock, as
`auvdiag inspect` prints its span: seconds (since 1970 for ROS, CSV, MCAP and tlog logs,
since boot for DataFlash and ULog) or ISO 8601 with a time zone; empty: from the log's start,
to its end. A log not listed is used whole, so a flight that failed late still gives its
healthy first minutes."""

import csv
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from auvdiag_cli.engine.ingest import WHOLE, Part
from auvdiag_errors import UsageError

COLUMNS = ("log", "start", "end")
NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class HealthyParts:
    """Each listed log's healthy part, keyed as the file names it."""

    source: Path | None = None
    parts: dict[str, Part] = field(default_factory=dict)

    def of(self, log: Path) -> Part:
        """The part listed for ``log`` (by its path as given, resolved, or its name);
        the whole log where none is."""
        for key in (str(log), str(log.resolve()), log.name):
            if key in self.parts:
                return self.parts[key]
        return WHOLE

    def described(self, log: Path) -> str | None:
        """What is used of ``log``, for progress; None when it is used whole."""
        start, end = self.of(log)
        if (start, end) == WHOLE:
            return None
        def when(ns: int | None, open_end: str) -> str:
            return open_end if ns is None else f"{ns / NS_PER_S:.3f} s"
        return f"{log.name}: only its healthy part, {when(start, 'its start')} to " \
               f"{when(end, 'its end')}"

    def unused(self, logs: list[Path]) -> list[str]:
        """Listed logs that none of ``logs`` is."""
        used = {key for log in logs for key in (str(log), str(log.resolve()), log.name)}
        return [key for key in self.parts if key not in used]


NO_HEALTHY_PARTS = HealthyParts()


def _time_ns(text: str, where: str) -> int | None:
    text = text.strip()
    if not text:
        return None
    try:
        return round(float(text) * NS_PER_S)
    except ValueError:
        pass
    try:
        moment = datetime.fromisoformat(text)
    except ValueError:
        raise UsageError(f"{where}: {text!r} is neither seconds nor an ISO 8601 time") from None
    if moment.tzinfo is None:
        raise UsageError(f"{where}: {text!r} has no time zone (add +00:00 for UTC)")
    return round(moment.timestamp() * NS_PER_S)


def read_healthy_parts(path: Path) -> HealthyParts:
    """The file's rows; a `UsageError` naming the file and row for anything wrong."""
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            rows = list(csv.reader(stream))
    except (OSError, UnicodeDecodeError) as error:
        raise UsageError(f"{path}: cannot read the healthy parts ({error})") from None
    header = [cell.strip() for cell in rows[0]] if rows else []
    if header[:3] != list(COLUMNS):
        raise UsageError(f"{path}: the healthy parts need the header log,start,end "
                         f"(found {','.join(header) or 'an empty file'})")
    parts: dict[str, Part] = {}
    for number, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        where = f"{path} line {number}"
        if len(row) < 3:
            raise UsageError(f"{where}: expected log,start,end")
        log = row[0].strip()
        part = (_time_ns(row[1], where), _time_ns(row[2], where))
        if part[0] is not None and part[1] is not None and part[1] <= part[0]:
            raise UsageError(f"{where}: the end is not after the start")
        if log in parts:
            raise UsageError(f"{where}: {log} is listed twice")
        parts[log] = part
    return HealthyParts(path, parts)


def announce_healthy_parts(healthy: HealthyParts, logs: Sequence[Path],
                           progress: Callable[[str], None]) -> None:
    """Say which logs are used only in part, and which listed logs were not given."""
    for log in logs:
        described = healthy.described(log)
        if described is not None:
            progress(described)
    unused = healthy.unused(list(logs))
    if unused:
        progress(f"warning: {healthy.source}: {len(unused)} listed log(s) not among those "
                 f"given: {', '.join(unused[:5])}" + (" …" if len(unused) > 5 else ""))
