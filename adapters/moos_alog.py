"""MOOS-IvP `.alog` files: the text log `pLogger` writes on most marine autonomy stacks.

A line is ``TIME VARIABLE SOURCE VALUE``: seconds since the header's ``%% LOGSTART`` (a
UNIX time), the MOOS variable posted, the app that posted it, and the posting (a number,
or text to the end of the line). A profile maps a signal to a variable
(``{ variable = "NAV_DEPTH" }``, its number as the field ``value``) or to one key of a
text posting of ``KEY=VALUE`` pairs (``{ variable = "NODE_REPORT_LOCAL", field = "SPD" }``);
``where = { source = "pNav" }`` keeps the postings of one app (the app alone where
pLogger's ``LogAuxSrc`` logs ``pHelmIvP:loiter``; ``source_aux`` is the rest). MOOS has no
boolean type: ``true`` and ``false`` read as 1 and 0 (``DEPLOY``,
``MOOS_MANUAL_OVERRIDE``).

Only the lines of the profile's variables are decoded; a line that does not read (damaged
bytes, a time that is no number) is left out and counted, and a last line without its
newline (a log cut short) is left out and the log read as damaged there."""

import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from itertools import compress
from pathlib import Path

import numpy as np

from adapters.collect import SignalCollector
from adapters.compressed import Chunks
from adapters.inventory import LogInventory, TopicInfo
from adapters.recognise import ALOG_LOGSTART as LOGSTART
from adapters.signals import MOOS_SOURCE as SOURCE
from adapters.signals import MOOS_SOURCE_AUX as SOURCE_AUX
from adapters.signals import MOOS_VALUE as VALUE
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

NUMBER_TYPE, TEXT_TYPE = "double", "string"
WORDS = {"true": 1.0, "false": 0.0}
MAX_UNIX_S = 2**32            # a LOGSTART beyond (year 2106) is no clock: damage
MAX_LOG_S = 2.0**32           # nor is a posting's time as far past the start
PAIR_SEPARATOR, KEY_SEPARATOR = ",", "="
AUX_SEPARATOR = ":"           # app:aux in the source column (pLogger's LogAuxSrc)
CUT_SHORT = "the log ends inside a line (cut short?): that line is left out"


# Read in blocks of whole lines (4 MB): a long log never sits in memory at once, and a
# block's postings, an object each while they are sorted by variable, stay a few tens of MB.
BLOCK_BYTES = 1 << 22
TAIL_BYTES = 1 << 16          # a block's last postings are found in this much of its end
_TOKEN = rb"[^ \t\r\n]+"
_TIME = rb"[0-9.+-][^ \t\r\n]*"      # what may be a time (checked when converted)
# A line that cannot be a posting: it starts with neither a time nor a header's `%`.
_NOT_A_POSTING = re.compile(rb"^[ \t]*[^%\s0-9.+-]", re.MULTILINE)
_LOGSTART_LINE = re.compile(re.escape(LOGSTART) + rb"[ \t]+(" + _TOKEN + rb")", re.MULTILINE)


def _posting_line(variables: bytes) -> re.Pattern[bytes]:
    """A line posting one of ``variables`` (a pattern): its time, variable, source, and
    value (the rest of the line, perhaps empty, its trailing blanks with it)."""
    return re.compile(rb"^[ \t]*(" + _TIME + rb")[ \t]+(" + variables + rb")[ \t]+("
                      + _TOKEN + rb")[ \t]*([^\r\n]*)", re.MULTILINE)


_ANY_POSTING = _posting_line(_TOKEN)


@dataclass
class _Postings:
    """One variable's postings, block by block: their times (s since LOGSTART), and their
    sources and values, each block's joined by newlines (no posting holds one), so that a
    long log's postings cost their text, not an object each."""

    times: list[np.ndarray] = field(default_factory=list)
    source_blocks: list[bytes] = field(default_factory=list)
    value_blocks: list[bytes] = field(default_factory=list)

    def add(self, times_s: np.ndarray, sources: list[bytes], values: list[bytes]) -> None:
        self.times.append(times_s)
        self.source_blocks.append(b"\n".join(sources))
        self.value_blocks.append(b"\n".join(value.rstrip() for value in values))

    @property
    def times_s(self) -> np.ndarray:
        return np.concatenate(self.times)

    @property
    def sources(self) -> list[bytes]:
        return [source for block in self.source_blocks for source in block.split(b"\n")]

    @property
    def values(self) -> list[bytes]:
        return [value for block in self.value_blocks for value in block.split(b"\n")]


@dataclass
class ParsedAlog:
    """What was read: the header's start (UNIX ns; None without one), each wanted variable's
    postings, every variable's count (inventory), the span of the lines' times and the
    lines left out."""

    logstart_ns: int | None = None
    postings: dict[str, _Postings] = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    first_s: float | None = None
    last_s: float | None = None
    unreadable: int = 0
    cut_short: bool = False
    stopped: str | None = None           # a compressed log's damage: read up to it
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


def _blocks(path: Path, parsed: ParsedAlog) -> Iterator[bytes]:
    """The file (decompressed, where it is an `.alog.gz`) in blocks of whole lines; a last
    line without its newline was cut short: left out (``parsed.cut_short``), as is what
    follows a compressed stream's damage (``parsed.stopped``)."""
    rest = b""
    chunks = Chunks(path, BLOCK_BYTES)
    for chunk in chunks:
        block = rest + chunk
        end = block.rfind(b"\n") + 1
        rest = block[end:]
        if end:
            yield block[:end]
    parsed.cut_short = bool(rest.strip())
    parsed.stopped = chunks.stopped


def _numbers(texts: Sequence[bytes]) -> np.ndarray:
    """Texts as float64, NaN where one is no finite number (`_reading`: true and false
    read too)."""
    try:
        numbers = np.fromiter(map(float, texts), np.float64, len(texts))
    except ValueError:
        numbers = np.array([_reading(text.decode("utf-8", "replace")) for text in texts],
                           np.float64)
    numbers[~np.isfinite(numbers)] = np.nan
    return numbers


def parse_alog(path: Path, wanted: set[str] | None) -> ParsedAlog:
    """The postings of ``wanted`` variables (None: every variable's count, first posting
    and who posts it, for inventory)."""
    parsed = ParsedAlog()
    pattern = _ANY_POSTING if wanted is None else _posting_line(b"|".join(
        re.escape(name.encode()) for name in sorted(wanted, key=len, reverse=True)))
    for block in _blocks(path, parsed):
        if parsed.logstart_ns is None and (start := _LOGSTART_LINE.search(block)):
            parsed.logstart_ns = _start_ns(start.group(1))
        parsed.unreadable += len(_NOT_A_POSTING.findall(block))
        _widen(parsed, _numbers(_ends(block)))
        found: dict[bytes, list[tuple[bytes, ...]]] = {}
        for line in pattern.findall(block):
            found.setdefault(line[1], []).append(line)
        for variable, lines in found.items():
            _keep(parsed, variable, lines, wanted is None)
    return parsed


def _ends(block: bytes) -> list[bytes]:
    """The times of a block's first and last postings (pLogger writes in time order)."""
    first = _ANY_POSTING.search(block)
    tail = block.rfind(b"\n", 0, max(0, len(block) - TAIL_BYTES)) + 1
    last = _ANY_POSTING.findall(block, tail)
    return ([first.group(1)] if first else []) + ([last[-1][0]] if last else [])


def _keep(parsed: ParsedAlog, variable: bytes, lines: list[tuple[bytes, ...]],
          inventory: bool) -> None:
    """A variable's lines of a block as postings; those whose time does not read are
    counted. For inventory, only its first posting is kept."""
    stamps, _, sources, values = (list(column) for column in zip(*lines, strict=True))
    times = _numbers(stamps)
    timed = _readable(times)
    try:
        name = variable.decode("ascii")
    except UnicodeDecodeError:
        timed[:] = False
    parsed.unreadable += int(timed.size - np.count_nonzero(timed))
    if not timed.all():
        sources, values = (list(compress(column, timed.tolist())) for column in (sources, values))
        times = times[timed]
    if not times.size:
        return
    parsed.counts[name] = parsed.counts.get(name, 0) + times.size
    _widen(parsed, times)
    if inventory:
        parsed.posters.setdefault(name, set()).update(
            _app_and_aux(source.decode("utf-8", "replace"))[0] for source in set(sources))
        if name in parsed.postings:
            return
        sources, values, times = sources[:1], values[:1], times[:1]
    parsed.postings.setdefault(name, _Postings()).add(times, sources, values)


def _readable(times_s: np.ndarray) -> np.ndarray:
    """Times a log can hold (NaN compares false: no time)."""
    return (times_s >= 0) & (times_s < MAX_LOG_S)


def _widen(parsed: ParsedAlog, times_s: np.ndarray) -> None:
    """The span read so far, widened to these times (those that read)."""
    times_s = times_s[_readable(times_s)]
    if times_s.size:
        first, last = float(times_s.min()), float(times_s.max())
        parsed.first_s = first if parsed.first_s is None else min(parsed.first_s, first)
        parsed.last_s = last if parsed.last_s is None else max(parsed.last_s, last)


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


def _texts(values: list[bytes]) -> list[str]:
    return [value.decode("utf-8", "replace") for value in values]


def _column(postings: _Postings, path: str) -> np.ndarray:
    """One field of every posting: numbers (NaN where a posting holds none), or the texts
    where no posting holds a number (segment labels, `where` on the source)."""
    if path in (SOURCE, SOURCE_AUX):
        split = [_app_and_aux(text) for text in _texts(postings.sources)]
        return np.asarray([parts[path == SOURCE_AUX] for parts in split], object)
    if path == VALUE:
        values = postings.values
        numbers = _numbers(values)
        texts = _texts(values) if np.isnan(numbers).all() else []
    else:
        texts = [pairs(text).get(path, "") for text in _texts(postings.values)]
        numbers = np.array([_reading(text) for text in texts], np.float64)
    if np.isnan(numbers).all() and any(texts):
        return np.asarray(texts, object)
    return numbers


def _clock_ns(parsed: ParsedAlog, times_s: np.ndarray | float) -> np.ndarray:
    """Seconds since LOGSTART on the log's clock: ns since 1970 (since the log's start
    where the header gives none)."""
    start_ns = parsed.logstart_ns or 0
    return start_ns + np.round(np.asarray(times_s, np.float64) * 1e9).astype(np.int64)


def _app_and_aux(source: str) -> tuple[str, str]:
    """The app that posted, and what pLogger's `LogAuxSrc` adds after a colon (the helm's
    behaviour: ``pHelmIvP:loiter``; "" where it adds nothing)."""
    app, _, aux = source.partition(AUX_SEPARATOR)
    return app, aux


def _fields(postings: _Postings) -> tuple[str, ...]:
    """The paths a profile can name on a variable: its value, its source (and the source's
    aux where pLogger logged one), and the keys of its first text posting."""
    first = postings.value_blocks[0].split(b"\n", 1)[0].decode("utf-8", "replace")
    keys = [key for key in pairs(first) if key not in (VALUE, SOURCE, SOURCE_AUX)]
    aux = (SOURCE_AUX,) if AUX_SEPARATOR.encode() in postings.source_blocks[0] else ()
    return (VALUE, SOURCE, *aux, *keys)


def _notes(parsed: ParsedAlog) -> list[str]:
    notes = []
    if parsed.unreadable:
        notes.append(f"{parsed.unreadable} line(s) that do not read as TIME VARIABLE SOURCE "
                     "VALUE left out")
    if parsed.logstart_ns is None:
        notes.append("no %% LOGSTART header: times are seconds from the log's start")
    return notes


def _damage(parsed: ParsedAlog) -> list[str]:
    """Where the log could be read only in part (a compressed stream's damage first)."""
    return [reason for reason in (parsed.stopped, CUT_SHORT if parsed.cut_short else None)
            if reason]


def _span_ns(parsed: ParsedAlog) -> tuple[int | None, int | None]:
    if parsed.first_s is None or parsed.last_s is None:
        return None, None
    return int(_clock_ns(parsed, parsed.first_s)), int(_clock_ns(parsed, parsed.last_s))


class MoosAlogAdapter:
    family = "moos"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        collector = SignalCollector(path, sources)
        parsed = parse_alog(path, set(collector.topics))
        if parsed.first_s is None:
            raise LogError(path, "no line reads as TIME VARIABLE SOURCE VALUE")
        for damage in _damage(parsed):
            collector.damaged(damage)
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
            number = not np.isnan(_numbers(postings.values[:1])[0])
            posters = tuple(sorted(parsed.posters.get(variable, ())))
            topics.append(TopicInfo(variable, NUMBER_TYPE if number else TEXT_TYPE, count,
                                    _fields(postings),
                                    ((SOURCE, posters),) if len(posters) > 1 else ()))
        start, end = _span_ns(parsed)
        notes = _notes(parsed) + _damage(parsed)
        return LogInventory(fmt, start, end, topics, notes)
