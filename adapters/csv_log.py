"""CSV logs: a header row naming the columns, then a row per sample. Recognised by content
(text whose first line names columns and whose next line has as many cells, some of them
numbers), never by the file name.

A signal is a column (`[sources.csv.signals]`: ``{ column = "depth", scale, offset }``); the
clock is another (`[sources.csv] time = { column, unit }`). An empty cell means no sample of
that column in that row, so logs that write each sensor on its own rows read as they are.
Rows with the wrong number of cells, unreadable times and cells that are not numbers are
left out and counted, never fatal unless nothing is left. A clock with one-second resolution
(``unit = "hhmmss"``) gets the rows of each second spread evenly over it."""

import csv
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from adapters.collect import SignalCollector
from adapters.compressed import DAMAGED_STREAM, damage, open_text
from adapters.extractor import ColumnSource
from adapters.fieldnames import closest_first
from adapters.inventory import LogInventory, TopicInfo
from adapters.recognise import csv_delimiter, is_number
from adapters.signals import LogSources, Signals, TimeColumn
from auvdiag_errors import LogError

UNIT_NS = {"s": 1e9, "ms": 1e6, "us": 1e3, "ns": 1.0}
SECONDS_PER_DAY = 86_400


class CsvRows:
    """The rows of a CSV file, the header first (the delimiter found in it). A row the csv
    module cannot parse (a stray quote that runs a field past its size limit) ends the
    rows there; ``stopped`` then says where and why: the file is damaged from there on."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.stopped: str | None = None

    def __iter__(self) -> Iterator[list[str]]:
        with open_text(self.path) as stream:      # a `.csv.gz` decompressed as it is read
            try:
                first = stream.readline()
                stream.seek(0)
                reader = csv.reader(stream, delimiter=csv_delimiter(first))
                yield from reader
            except csv.Error as error:
                self.stopped = f"unreadable from line {reader.line_num} ({error})"
            except DAMAGED_STREAM as error:
                self.stopped = damage(error)


def csv_rows(path: Path) -> Iterator[list[str]]:
    """The rows of a CSV log up to any damage (`CsvRows`)."""
    return iter(CsvRows(path))


class _Parsed:
    """The cells a profile needs, as columns, with what had to be left out."""

    def __init__(self) -> None:
        self.times: list[str] = []
        self.cells: dict[str, list[str]] = {}
        self.wrong_width = self.blank = 0
        self.stopped: str | None = None        # where the file became unreadable


def _parse(path: Path, wanted: list[str], time_column: str, optional: set[str]
           ) -> tuple[_Parsed, list[str]]:
    """The ``wanted`` columns' cells; a column of ``optional`` the header lacks is left
    out of them."""
    table = CsvRows(path)
    rows = iter(table)
    header = [name.strip() for name in next(rows, [])]
    wanted = [name for name in wanted if name in header or name not in optional]
    missing = [name for name in dict.fromkeys([time_column, *wanted]) if name not in header]
    if missing:
        offered = ", ".join(closest_first(missing[0], header))
        raise LogError(path, f"no column(s) {', '.join(missing)} in the header (its columns, "
                             f"closest first: {offered})")
    where = {name: header.index(name) for name in wanted}
    time_at, width = header.index(time_column), len(header)
    parsed = _Parsed()
    parsed.cells = {name: [] for name in wanted}
    for row in rows:
        if len(row) != width:
            if any(cell.strip() for cell in row):
                parsed.wrong_width += 1
            else:
                parsed.blank += 1
            continue
        parsed.times.append(row[time_at].strip())
        for name, at in where.items():
            parsed.cells[name].append(row[at].strip())
    parsed.stopped = table.stopped
    return parsed, header


def _spread_seconds(seconds: np.ndarray, notes: list[str], column: str) -> np.ndarray:
    """Times in s for a clock that only counts whole seconds: the rows of a second are
    spread evenly over it; the first and last (partial) seconds at the usual rate."""
    starts = np.flatnonzero(np.diff(seconds, prepend=np.nan) != 0)
    counts = np.diff(np.append(starts, seconds.size))
    rate = float(np.median(counts[1:-1])) if counts.size > 2 else float(counts.max())
    offsets = np.empty(seconds.size)
    for group, (start, count) in enumerate(zip(starts, counts, strict=True)):
        step = 1.0 / max(rate, count)
        index = np.arange(count)
        if group == 0 and counts.size > 1:
            offsets[start:start + count] = 1.0 - (count - index) * step   # end of its second
        elif group == counts.size - 1 and counts.size > 1:
            offsets[start:start + count] = index * step
        else:
            offsets[start:start + count] = index / count
    notes.append(f"time column {column!r} has one-second resolution: the rows of each second "
                 f"are spread evenly over it (about {rate:g} rows a second)")
    return seconds + offsets


def _times_ns(texts: list[str], time: TimeColumn, notes: list[str]) -> np.ndarray:
    """Row times in ns (int64), NaN-free; an unreadable time is -1."""
    if time.unit == "iso":
        def iso(text: str) -> float:
            moment = datetime.fromisoformat(text)
            return (moment if moment.tzinfo else moment.replace(tzinfo=UTC)).timestamp()
        return np.array([round(iso(t) * 1e9) if _readable(iso, t) else -1 for t in texts],
                        np.int64)
    values = np.array([float(t) if is_number(t) else np.nan for t in texts])
    if time.unit == "hhmmss":
        whole = np.floor(values)
        hours, minutes, seconds = whole // 10_000, whole // 100 % 100, whole % 100
        valid = (hours < 24) & (minutes < 60) & (seconds < 60) & (values >= 0)
        day_seconds = np.where(valid, hours * 3600 + minutes * 60 + seconds, np.nan)
        kept = ~np.isnan(day_seconds)
        if kept.any():   # past midnight the clock starts again: count the days
            clock = day_seconds[kept]
            clock += np.cumsum(np.diff(clock, prepend=clock[0]) < -SECONDS_PER_DAY / 2
                               ) * SECONDS_PER_DAY
            day_seconds[kept] = _spread_seconds(clock, notes, time.column)
        values = day_seconds * 1e9
    else:
        values = values * UNIT_NS[time.unit]
    usable = np.isfinite(values) & (values >= 0) & (values < 2.0**62)
    return np.where(usable, np.round(np.where(usable, values, 0.0)), -1).astype(np.int64)


def _constant(values: np.ndarray) -> ColumnSource:
    """A column source for one CSV column (whatever path is asked, it is this column)."""
    def column(_: str) -> np.ndarray:
        return values

    return column


def _readable(parse: object, text: str) -> bool:
    try:
        parse(text)  # type: ignore[operator]
    except (ValueError, OverflowError, OSError):
        return False
    return True


class CsvAdapter:
    """A CSV log with a header row (comma, semicolon or tab separated)."""

    family = "csv"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        if sources.time is None:
            raise LogError(path, "the profile's [sources.csv] does not say which column holds "
                                 "the time (time = { column = ..., unit = ... })")
        collector = SignalCollector(path, sources)
        segment = sources.segment
        required = {s.topic for n, s in sources.signals.items() if n not in sources.optional}
        optional = {s.topic for s in sources.signals.values()} - required
        parsed, header = _parse(path, sorted(collector.topics), sources.time.column, optional)
        wanted = list(parsed.cells)
        # Columns read through a `values` map: their texts (a mode's name) are the values.
        looked_up = {s.topic for s in sources.signals.values() if s.mapped}
        times = _times_ns(parsed.times, sources.time, collector.notes)
        timed = times >= 0
        bad_values = 0
        for name in wanted:
            cells = np.asarray(parsed.cells[name], dtype=object)
            present = timed & (cells != "")
            texts = cells[present]
            if (segment is not None and name == segment.topic) or name in looked_up:
                collector.add_columns(name, times[present], _constant(texts), header)
                continue
            readable = np.array([is_number(text) for text in texts.tolist()], bool)
            numbers = np.array([float(text) for text in texts[readable].tolist()], np.float64)
            bad_values += int((~readable).sum())
            collector.add_columns(name, times[present][readable], _constant(numbers), header)
        self._count_losses(collector, parsed, int((~timed).sum()), bad_values)
        if parsed.stopped is not None:
            collector.damaged(f"CSV {parsed.stopped}")
            collector.notes.append(f"read up to the damage: {parsed.stopped}")
        return collector.finish("csv", None, None, {name: "CSV column" for name in header})

    @staticmethod
    def _count_losses(collector: SignalCollector, parsed: _Parsed, bad_times: int,
                      bad_values: int) -> None:
        lost = [f"{count} {what}" for count, what in (
            (parsed.wrong_width, "row(s) with the wrong number of cells"),
            (bad_times, "row(s) whose time does not read"),
            (bad_values, "cell(s) that are not numbers")) if count]
        if lost:
            collector.notes.append("left out: " + "; ".join(lost))

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        """Every column with its count of non-empty cells (the time column is not known
        without a profile, so there is no span)."""
        rows = csv_rows(path)
        header = [name.strip() for name in next(rows, [])]
        counts = [0] * len(header)
        for row in rows:
            if len(row) == len(header):
                for at, cell in enumerate(row):
                    counts[at] += bool(cell.strip())
        return LogInventory("csv", None, None, [TopicInfo(name, "CSV column", count)
                                                for name, count in zip(header, counts,
                                                                       strict=True)])
