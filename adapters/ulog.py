"""PX4 ULog logs (.ulg), decoded column-wise (`adapters.ulog_decode`); a log with appended
data (written after a crash) goes through pyulog instead.

A signal is a topic and a field as pyulog names it (``vehicle_angular_velocity`` and
``xyz[2]``, ``actuator_motors`` and ``control[0]``). A topic logged in several instances
(two gyros, two actuator output groups) carries an ``instance`` column, the ULog multi id:
a profile chooses one with ``where = { instance = 0 }`` (mixing them is refused, as for
DataFlash sensor instances). Logged text messages are the pseudo-topic ``logging`` with the
field ``message`` (segment markers). Times are the log's timestamps, µs since boot. Only the
profile's topics are decoded. Damaged bytes are skipped up to the next sync marker and a
truncation ends the log; both are reported, and the part read is analysed."""

import contextlib
import io
import mmap
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adapters.autopilot_messages import ulog_messages
from adapters.collect import SignalCollector
from adapters.extractor import ColumnSource
from adapters.inventory import LogInventory, TopicInfo
from adapters.signals import LogSources, Signals
from adapters.ulog_decode import (
    HEADER_BYTES,
    TIMESTAMP,
    AppendedData,
    DecodedUlog,
    DefinitionsDamaged,
    Instance,
    decode_ulog,
)
from auvdiag_errors import LogError

INSTANCE = "instance"
LOGGING_TOPIC = "logging"


def _definitions_damaged(path: Path, at: int) -> LogError:
    return LogError(path, f"the ULog's definitions (message formats, parameters) are "
                          f"damaged at byte {at}: its messages cannot be decoded")


def decoded_ulog(path: Path, topics: set[str] | None) -> DecodedUlog:
    """The log's messages (only ``topics`` decoded; None: all), its errors as LogError."""
    try:
        return decode_ulog(path.read_bytes(), topics)
    except DefinitionsDamaged as damaged:
        raise _definitions_damaged(path, damaged.at) from None
    except AppendedData:
        return _through_pyulog(path, topics)
    except MemoryError:
        raise
    except Exception as error:   # an incompatible or unreadable log: one line, not a trace
        raise LogError(path, f"not a readable ULog: {type(error).__name__}: {error}") from None


def _through_pyulog(path: Path, topics: set[str] | None) -> DecodedUlog:
    """pyulog's parse, which follows appended offsets. It prints warnings about damaged
    bytes: they become notes, not terminal output."""
    from pyulog import ULog

    framing = walk_framing(path)
    if framing.definitions_damaged_at is not None:
        raise _definitions_damaged(path, framing.definitions_damaged_at)
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            ulog = ULog(str(path), message_name_filter_list=None if topics is None else
                        sorted(topics), disable_str_exceptions=True)
    except MemoryError:
        raise
    except Exception as error:   # pyulog raises what the bytes make it raise: wrap it
        raise LogError(path, f"not a readable ULog: {type(error).__name__}: {error}") from None
    decoded = DecodedUlog(int(ulog.start_timestamp), corrupt=bool(ulog.file_corruption),
                          cut_at=framing.cut_at, last_us=int(ulog.last_timestamp))
    for data in ulog.data_list:
        decoded.topics.setdefault(data.name, []).append(Instance(data.multi_id, data.data))
    decoded.logged = [(int(m.timestamp), m.message, int(m.log_level))
                      for m in ulog.logged_messages]
    decoded.dropouts_ms = [int(d.duration) for d in ulog.dropouts]
    return decoded


def _topic_columns(instances: list[Instance]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A topic's instances as one table: times (ns) and columns (fields and ``instance``)."""
    names = [n for n in instances[0].columns if all(n in d.columns for d in instances)]
    columns = {name: np.concatenate([d.columns[name] for d in instances]) for name in names}
    columns[INSTANCE] = np.concatenate([
        np.full(d.columns[TIMESTAMP].size, d.multi_id, np.int64) for d in instances])
    return columns[TIMESTAMP].astype(np.int64) * 1000, columns


def _column_source(columns: dict[str, np.ndarray]) -> ColumnSource:
    def column(path: str) -> np.ndarray:
        return columns[path]
    return column


class UlogAdapter:
    family = "ulog"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        collector = SignalCollector(path, sources)
        wanted = collector.topics - {LOGGING_TOPIC}
        decoded = decoded_ulog(path, wanted)
        for topic in sorted(wanted & decoded.topics.keys()):
            times_ns, columns = _topic_columns(decoded.topics[topic])
            collector.add_columns(topic, times_ns, _column_source(columns), tuple(columns))
        if LOGGING_TOPIC in collector.topics:
            for time_us, text, _ in decoded.logged:
                collector.add(LOGGING_TOPIC, time_us * 1000, {"message": text})
        _note_damage(decoded, collector)
        signals = collector.finish("ulog", decoded.start_us * 1000, decoded.last_us * 1000,
                                   dict.fromkeys(decoded.topics, "ULog"))
        signals.autopilot_messages = ulog_messages(decoded.logged)
        return signals

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        decoded = decoded_ulog(path, None)
        topics = []
        for name, instances in sorted(decoded.topics.items()):
            _, columns = _topic_columns(instances)
            ids = tuple(str(d.multi_id) for d in instances)
            topics.append(TopicInfo(name, "ULog", int(columns[TIMESTAMP].size),
                                    tuple(n for n in columns if n != TIMESTAMP),
                                    ((INSTANCE, ids),) if len(ids) > 1 else ()))
        if decoded.logged:
            topics.append(TopicInfo(LOGGING_TOPIC, "ULog text", len(decoded.logged),
                                    ("message",)))
        notes = [DAMAGE_TEXT] if decoded.corrupt else []
        return LogInventory("ulog", decoded.start_us * 1000, decoded.last_us * 1000, topics,
                            notes, ulog_messages(decoded.logged))

DEFINITION_KINDS = b"BFIMPQ"     # flag bits, formats, info, parameters
DATA_KINDS = b"ALC"              # subscriptions and text messages begin the data section


@dataclass(frozen=True)
class Framing:
    """What a walk over the message headers finds: where the definitions are damaged (pyulog
    can loop for ever on some of those), and where a cut file's last message begins (pyulog
    stops there silently). None where nothing is wrong, or damage earlier hides it."""

    definitions_damaged_at: int | None = None
    cut_at: int | None = None


def walk_framing(path: Path) -> Framing:
    size = path.stat().st_size
    if size < HEADER_BYTES:
        return Framing(cut_at=0)
    with path.open("rb") as stream, mmap.mmap(stream.fileno(), 0,
                                               access=mmap.ACCESS_READ) as data:
        header = struct.Struct("<HB")
        at, in_definitions = HEADER_BYTES, True
        while at + header.size <= size:
            length, kind = header.unpack_from(data, at)
            if in_definitions and kind in DATA_KINDS:
                in_definitions = False
            broken = kind == 0 or length == 0 or at + header.size + length > size
            if in_definitions and (broken or kind not in DEFINITION_KINDS):
                return Framing(definitions_damaged_at=at)
            if broken:
                return Framing(cut_at=at if kind and length else None)
            at += header.size + length
        if in_definitions:
            return Framing(definitions_damaged_at=at)
        return Framing(cut_at=None if at == size else at)


DAMAGE_TEXT = ("damaged bytes in the ULog: skipped to the next readable message, so some "
               "messages are missing")


def _note_damage(decoded: DecodedUlog, collector: SignalCollector) -> None:
    if decoded.corrupt:
        collector.notes.append(DAMAGE_TEXT)
        collector.damaged(DAMAGE_TEXT)
    cut = decoded.cut_at
    if cut is not None:
        reason = f"the ULog ends inside a message at byte {cut}: the file was cut short"
        collector.notes.append(reason)
        collector.damaged(reason, cut)
    dropped_ms = sum(decoded.dropouts_ms)
    if dropped_ms:
        collector.notes.append(f"the logger dropped data {len(decoded.dropouts_ms)} time(s), "
                               f"{dropped_ms} ms in all")
