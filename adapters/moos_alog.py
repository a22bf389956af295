"""MOOS-IvP `.alog` files: the text log `pLogger` writes on most marine autonomy stacks.

A line is ``TIME VARIABLE SOURCE VALUE``: seconds since the header's ``%% LOGSTART`` (a
UNIX time), the MOOS variable posted, the app that posted it, and the posting (a number,
or text to the end of the line). A profile maps a signal to a variable
(``{ variable = "NAV_DEPTH" }``, its number as the field ``value``) or to one key of a
text posting of ``KEY=VALUE`` pairs (``{ variable = "NODE_REPORT_LOCAL", field = "SPD" }``);
``where = { source = "pNav" }`` keeps the postings of one app. MOOS has no boolean type:
``true`` and ``false`` read as 1 and 0 (``DEPLOY``, ``MOOS_MANUAL_OVERRIDE``).

Only the lines of the profile's variables are decoded; a line that does not read (a log cut
short mid-line, bytes that are no text) is left out and counted."""

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np

from adapters.collect import SignalCollector
from adapters.inventory import LogInventory, TopicInfo
from adapters.recognise import ALOG_LOGSTART as LOGSTART
from adapters.signals import MOOS_SOURCE as SOURCE
from adapters.signals import MOOS_VALUE as VALUE
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

NUMBER_TYPE, TEXT_TYPE = "double", "string"
WORDS = {"true": 1.0, "false": 0.0}
MAX_UNIX_S = 2**32            # a LOGSTART beyond (year 2106) is no clock: damage
PAIR_SEPARATOR, KEY_SEPARATOR = ",", "="


@dataclass
class _Postings:
    """One variable's lines: their times (s since LOGSTART), sources and values as text."""

    times_s: list[float] = field(default_factory=list)
    sources: list[str] = field(default_factory=list)
    values: list[str] = field(default_factory=list)


@dataclass
class ParsedAlog:
    """What was read: the header's start (UNIX ns; None without one), each wanted variable's
    postings, every variable's count, the span of the lines' times and the lines left out."""

    logstart_ns: int | None
    postings: dict[str, _Postings]
    counts: dict[str, int]
    first_s: float | None = None
    last_s: float | None = None
    unreadable: int = 0
    cut_short: bool = False
    posters: dict[str, set[str]] = field(default_factory=dict)   # inventory: who posts each


def _number(text: bytes | str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _start_ns(text: bytes) -> int | None:
    """LOGSTART's UNIX seconds as ns, exactly (a float64 would round today's to 256 ns)."""
    try:
        start = Decimal(text.decode("ascii"))
    except (InvalidOperation, UnicodeDecodeError):
        return None
    return int(start * 10**9) if start.is_finite() and 0 <= start < MAX_UNIX_S else None


def _lines(path: Path) -> Iterator[bytes]:
    with path.open("rb") as stream:
        yield from stream


def parse_alog(path: Path, wanted: set[str] | None) -> ParsedAlog:
    """The postings of ``wanted`` variables (None: the first of each, and who posts each,
    for inventory). A last line without its newline was cut short: left out."""
    parsed = ParsedAlog(None, {}, {})
    keys = None if wanted is None else {name.encode() for name in wanted}
    for line in _lines(path):
        if not line.endswith(b"\n"):
            parsed.cut_short = True
            break
        if line.startswith(b"%%"):
            if line.startswith(LOGSTART) and parsed.logstart_ns is None:
                parsed.logstart_ns = _start_ns(line[len(LOGSTART):].strip())
            continue
        parts = line.split(None, 3)
        if parts:
            _take(parsed, parts, keys)
    return parsed


def _take(parsed: ParsedAlog, parts: list[bytes], keys: set[bytes] | None) -> None:
    """One line's posting, kept where its variable is wanted."""
    time_s = _number(parts[0]) if len(parts) >= 3 else None
    try:
        variable = parts[1].decode("ascii") if time_s is not None and time_s >= 0 else None
    except UnicodeDecodeError:
        variable = None
    if time_s is None or variable is None:
        parsed.unreadable += 1
        return
    count = parsed.counts[variable] = parsed.counts.get(variable, 0) + 1
    parsed.first_s = time_s if parsed.first_s is None else min(parsed.first_s, time_s)
    parsed.last_s = time_s if parsed.last_s is None else max(parsed.last_s, time_s)
    source = parts[2].decode("utf-8", "replace")
    if keys is None:
        parsed.posters.setdefault(variable, set()).add(source)
        if count > 1:
            return
    elif parts[1] not in keys:
        return
    postings = parsed.postings.setdefault(variable, _Postings())
    postings.times_s.append(time_s)
    postings.sources.append(source)
    postings.values.append(parts[3].decode("utf-8", "replace").rstrip("\r\n")
                           if len(parts) > 3 else "")


def _reading(text: str) -> float:
    """A posting's number: NaN (no reading) where it is none."""
    word = WORDS.get(text.strip().lower())
    if word is not None:
        return word
    number = _number(text)
    return math.nan if number is None else number


def pairs(text: str) -> dict[str, str]:
    """A text posting's ``KEY=VALUE`` pairs (none where it holds no such pair)."""
    found = {}
    for item in text.split(PAIR_SEPARATOR):
        key, equals, value = item.partition(KEY_SEPARATOR)
        if equals and key.strip():
            found[key.strip()] = value.strip()
    return found


def _column(postings: _Postings, path: str) -> np.ndarray:
    """One field of every posting: numbers (NaN where a posting holds none), or the texts
    where no posting holds a number (segment labels, `where` on the source)."""
    if path == SOURCE:
        return np.asarray(postings.sources, object)
    texts = postings.values if path == VALUE else [
        pairs(text).get(path, "") for text in postings.values]
    numbers = np.array([_reading(text) for text in texts], np.float64)
    if np.isnan(numbers).all() and any(texts):
        return np.asarray(texts, object)
    return numbers


def _clock_ns(parsed: ParsedAlog, times_s: list[float] | float) -> np.ndarray:
    """Seconds since LOGSTART on the log's clock: ns since 1970 (since the log's start
    where the header gives none)."""
    start_ns = parsed.logstart_ns or 0
    return start_ns + np.round(np.asarray(times_s, np.float64) * 1e9).astype(np.int64)


def _fields(postings: _Postings) -> tuple[str, ...]:
    """The paths a profile can name on a variable: its value, its source, and the keys of
    its first text posting."""
    first = postings.values[0] if postings.values else ""
    keys = [key for key in pairs(first) if key not in (VALUE, SOURCE)]
    return (VALUE, SOURCE, *keys)


def _notes(parsed: ParsedAlog) -> list[str]:
    notes = []
    if parsed.unreadable:
        notes.append(f"{parsed.unreadable} line(s) that do not read as TIME VARIABLE SOURCE "
                     "VALUE left out")
    if parsed.logstart_ns is None:
        notes.append("no %% LOGSTART header: times are seconds from the log's start")
    return notes


def _span_ns(parsed: ParsedAlog) -> tuple[int | None, int | None]:
    if parsed.first_s is None or parsed.last_s is None:
        return None, None
    return int(_clock_ns(parsed, parsed.first_s)), int(_clock_ns(parsed, parsed.last_s))


class MoosAlogAdapter:
    family = "moos"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        collector = SignalCollector(path, sources)
        parsed = parse_alog(path, set(collector.topics))
        if not parsed.counts:
            raise LogError(path, "no line reads as TIME VARIABLE SOURCE VALUE")
        if parsed.cut_short:
            collector.damaged("the log ends inside a line (cut short?): that line is left out")
        for variable in sorted(collector.topics & parsed.postings.keys()):
            postings = parsed.postings[variable]

            def column(path: str, postings: _Postings = postings) -> np.ndarray:
                return _column(postings, path)

            collector.add_columns(variable, _clock_ns(parsed, postings.times_s), column,
                                  _fields(postings))
        collector.notes.extend(_notes(parsed))
        start, end = _span_ns(parsed)
        return collector.finish(fmt, start, end, dict.fromkeys(parsed.counts, "MOOS"),
                                time_ordered=True)

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        parsed = parse_alog(path, None)
        topics = []
        for variable, count in sorted(parsed.counts.items()):
            postings = parsed.postings[variable]
            number = not math.isnan(_reading(postings.values[0])) if postings.values else False
            posters = tuple(sorted(parsed.posters.get(variable, ())))
            topics.append(TopicInfo(variable, NUMBER_TYPE if number else TEXT_TYPE, count,
                                    _fields(postings),
                                    ((SOURCE, posters),) if len(posters) > 1 else ()))
        start, end = _span_ns(parsed)
        notes = _notes(parsed) + (["the log ends inside a line (cut short?): that line is "
                                   "left out"] if parsed.cut_short else [])
        return LogInventory(fmt, start, end, topics, notes)
