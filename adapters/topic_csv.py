"""A ROS log exported as per-topic CSVs: a folder holding one CSV per topic, as
``rostopic echo -p`` (``%time`` in ns since 1970, then ``field.<path>`` columns) or bag-to-CSV
tools such as bagpy (``Time`` in s, then ``<path>`` columns) write them. The folder is one
log, read with the profile's ``[sources.ros]`` mapping, so that one profile reads a flight
from its bag and from its CSV export alike; one such CSV given alone is a log of one topic.

A file's topic is its name with the recording's name taken off the front and ``-`` read as
``/`` (ROS names hold no ``-``): ``flight-mavros-imu-data.csv`` in ``flight/`` is
``/mavros/imu/data``. The recording's name is the folder's, as the exports prefix it; in a
folder renamed since, it is what every file's name begins with up to its last ``-``-part
that starts with a digit (a ROS name's parts never do, a recording's date does:
``carbonZ_2018-07-30-17-20-01_engine_failure-mavros-imu-data.csv``). A profile's field
path ``channels[0]`` is the column ``field.channels0`` (``rostopic``'s flattening) or
``channels[0]``; a part of a ROS time (``header.stamp.sec``, ``nanosec``) is read from the
time rostopic writes whole (``field.header.stamp``, nanoseconds); ``%time`` (the time the
recorder received the message) is the clock, as a bag's record time is."""

import csv
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adapters.collect import SignalCollector
from adapters.csv_log import CsvRows
from adapters.fieldpath import parse_field_path
from adapters.inventory import LogInventory, TopicInfo
from adapters.recognise import (
    TOPIC_CSV_CLOCKS,
    TOPIC_CSV_FIELD_PREFIX,
    csv_delimiter,
    csv_header,
    first_line,
    is_number,
    topic_csv_clock,
    topic_csv_files,
)
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

TOPIC_TYPE = "per-topic CSV"


def topic_of(path: Path, recording: str) -> str:
    """The ROS topic a per-topic CSV holds, from its file name and the ``recording``'s name
    (see the module's note)."""
    stem = path.stem
    if stem.startswith(recording + "-"):
        stem = stem[len(recording) + 1:]
    return "/" + stem.replace("-", "/")


def recording_name(folder: Path, files: Sequence[Path]) -> str:
    """The name the exports put in front of each topic: the folder's where every file
    begins with it, else every file's common ``-``-parts up to the last that starts with a
    digit ("" where there is none)."""
    stems = [file.stem for file in files]
    if all(stem.startswith(folder.name + "-") for stem in stems):
        return folder.name
    split = [stem.split("-")[:-1] for stem in stems]
    common = 0
    while split and all(len(parts) > common and parts[common] == split[0][common]
                        for parts in split):
        common += 1
    dated = [i for i, part in enumerate(split[0][:common]) if part[:1].isdigit()] if split else []
    return "-".join(split[0][:dated[-1] + 1]) if dated else ""


def topic_files(path: Path) -> dict[str, Path]:
    """Topic → its CSV, for a folder of per-topic CSVs or one such CSV."""
    if not path.is_dir():
        return {topic_of(path, path.parent.name): path}
    found = topic_csv_files(path)
    recording = recording_name(path, found)
    files = {topic_of(file, recording): file for file in found}
    if not files:
        raise LogError(path, "the folder holds no per-topic CSV (a CSV whose header starts "
                             "with %time or Time)")
    return files


def column_names(path: str) -> list[str]:
    """The columns a field path may have in an export: ``status[0].name`` is
    ``field.status0.name`` (rostopic's flattening) or ``field.status[0].name``, with or
    without the ``field.`` prefix."""
    flattened = ""
    for step in parse_field_path(path):
        flattened += str(step) if isinstance(step, int) else ("." if flattened else "") + step
    return [prefix + form for form in dict.fromkeys((flattened, path))
            for prefix in (TOPIC_CSV_FIELD_PREFIX, "")]


# A ROS time's parts as a bag holds them (ROS 1 secs/nsecs, ROS 2 sec/nanosec); rostopic
# writes the whole time as one column of nanoseconds.
TIME_PARTS = {"sec": "seconds", "secs": "seconds", "nanosec": "nanoseconds",
              "nsecs": "nanoseconds"}


def time_part(path: str) -> tuple[str, str] | None:
    """(the time's own path, "seconds" or "nanoseconds") where ``path`` names a part of a
    ROS time (``header.stamp.sec``); None otherwise."""
    parent, _, last = path.rpartition(".")
    return (parent, TIME_PARTS[last]) if parent and last in TIME_PARTS else None


def _part_of_time(nanoseconds: np.ndarray, part: str) -> np.ndarray:
    """The seconds or the nanoseconds of a time read whole in nanoseconds."""
    seconds = np.floor(nanoseconds / 1e9)
    return seconds if part == "seconds" else nanoseconds - seconds * 1e9


@dataclass
class _Table:
    """One topic's CSV: its header, clock and the cells of the columns asked for."""

    header: list[str]
    times_ns: np.ndarray
    columns: dict[str, list[str]]
    wrong_width: int
    bad_times: int
    stopped: str | None          # where the file became unreadable (`CsvRows`)


def _read_table(path: Path, wanted: set[str]) -> _Table:
    header = csv_header(first_line(path))
    clock = topic_csv_clock(header)
    if clock is None:
        raise LogError(path, "not a per-topic CSV (its header does not start with %time or "
                             "Time)")
    picked = {name: at for at, name in enumerate(header) if name in wanted}
    texts: list[str] = []
    cells: dict[str, list[str]] = {name: [] for name in picked}
    wrong_width = 0
    table = CsvRows(path)
    rows = iter(table)
    next(rows, None)
    for row in rows:
        if len(row) != len(header):
            wrong_width += bool(any(cell.strip() for cell in row))
            continue
        texts.append(row[0].strip())
        for name, at in picked.items():
            cells[name].append(row[at].strip())
    times = _times_ns(texts, TOPIC_CSV_CLOCKS[clock])
    return _Table(header, times, cells, wrong_width, int((times < 0).sum()), table.stopped)


def _times_ns(texts: list[str], ns_per_unit: int) -> np.ndarray:
    """Clock cells to int64 ns; -1 where a cell does not read. Whole numbers of ns are
    read exactly (a float64 would round 2018's times to 256 ns)."""
    out = np.full(len(texts), -1, np.int64)
    for at, text in enumerate(texts):
        if ns_per_unit == 1 and text.isdigit() and len(text) < 25:
            exact = int(text)
            out[at] = exact if exact < 2**62 else -1
        elif is_number(text):
            value = float(text) * ns_per_unit
            if np.isfinite(value) and 0 <= value < 2.0**62:
                out[at] = round(value)
    return out


def _numbers(texts: list[str]) -> np.ndarray:
    return np.array([float(text) if is_number(text) else np.nan for text in texts],
                    np.float64)


class TopicCsvAdapter:
    """A folder of per-topic CSVs (or one of them), read as the ROS log it was exported
    from."""

    family = "ros"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        files = topic_files(path)
        collector = SignalCollector(path, sources)
        collector.resolve_topics(files)
        collector.require_topics(files)
        lost: dict[str, int] = {}
        for topic in sorted(collector.topics & files.keys()):   # less any optional one
            self._add_topic(collector, topic, files[topic], lost)
        if lost:
            collector.notes.append("left out: " + "; ".join(
                f"{count} {what}" for what, count in lost.items()))
        start, end = _span(files.values())
        return collector.finish(fmt, start, end, dict.fromkeys(files, TOPIC_TYPE),
                                time_ordered=True)

    @staticmethod
    def _add_topic(collector: SignalCollector, topic: str, file: Path,
                   lost: dict[str, int]) -> None:
        paths = collector.field_paths(topic)
        wholes = [whole[0] for path in paths if (whole := time_part(path)) is not None]
        wanted = {name for path in [*paths, *wholes] for name in column_names(path)}
        table = _read_table(file, wanted)
        for what, count in (("row(s) with the wrong number of cells", table.wrong_width),
                            ("row(s) whose time does not read", table.bad_times)):
            if count:
                lost[what] = lost.get(what, 0) + count
        if table.stopped is not None:
            collector.damaged(f"{file.name}: {table.stopped}")
            collector.notes.append(f"{topic} read up to the damage in {file.name}: "
                                   f"{table.stopped}")
        timed = table.times_ns >= 0
        fields = [_path_of(name) for name in table.header[1:]]

        def column(path: str) -> np.ndarray:
            for name in column_names(path):
                if name in table.columns:
                    cells = table.columns[name]
                    values = _numbers(cells)
                    texts_only = np.isnan(values).all() and any(cells)
                    return (np.asarray(cells, object) if texts_only else values)[timed]
            whole = time_part(path)     # a time rostopic wrote whole, in nanoseconds
            if whole is not None:
                for name in column_names(whole[0]):
                    if name in table.columns:
                        return _part_of_time(_numbers(table.columns[name]), whole[1])[timed]
            raise KeyError(path)

        collector.add_columns(topic, table.times_ns[timed], column, fields)

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        files = topic_files(path)
        topics = []
        for topic, file in sorted(files.items()):
            header = csv_header(first_line(file))
            rows = max(_line_count(file) - 1, 0)
            topics.append(TopicInfo(topic, TOPIC_TYPE, rows,
                                    tuple(_path_of(name) for name in header[1:])))
        start, end = _span(files.values())
        return LogInventory(fmt, start, end, topics)


def _path_of(column: str) -> str:
    return column.removeprefix(TOPIC_CSV_FIELD_PREFIX)


def _line_count(path: Path) -> int:
    with path.open("rb") as stream:
        return sum(chunk.count(b"\n") for chunk in iter(lambda: stream.read(1 << 20), b""))


def _span(files: Iterable[Path]) -> tuple[int | None, int | None]:
    """The first and last clock readings over the files (their first and last rows)."""
    firsts: list[int] = []
    lasts: list[int] = []
    for file in files:
        header = csv_header(first_line(file))
        clock = topic_csv_clock(header)
        if clock is None:
            continue
        first, last = _end_rows(file, len(header))
        times = _times_ns([row.split(csv_delimiter(row))[0].strip() for row in (first, last)],
                          TOPIC_CSV_CLOCKS[clock])
        firsts += [int(t) for t in times[:1] if t >= 0]
        lasts += [int(t) for t in times[1:] if t >= 0]
    return min(firsts, default=None), max(lasts, default=None)


def _end_rows(path: Path, width: int) -> tuple[str, str]:
    """The first data row and the last whole row (``width`` cells) of a CSV, reading only
    its ends: a file cut short ends in part of a row."""
    with path.open("rb") as stream:
        stream.readline()
        first = stream.readline().decode("utf-8", "replace").strip()
        size = stream.seek(0, 2)
        stream.seek(max(0, size - 16384))
        tail = stream.read().decode("utf-8", "replace").splitlines()
    whole = [row for row in tail[-3:] if _cells(row) == width]
    return first, (whole[-1] if whole else "")


def _cells(row: str) -> int:
    """How many cells one CSV line holds (0 for one the csv module cannot parse)."""
    try:
        return len(next(csv.reader([row]), []))
    except csv.Error:
        return 0
