"""PX4 ULog logs (.ulg), read with pyulog.

A signal is a topic and a field as pyulog names it (``vehicle_angular_velocity`` and
``xyz[2]``, ``actuator_motors`` and ``control[0]``). A topic logged in several instances
(two gyros, two actuator output groups) carries an ``instance`` column, the ULog multi id:
a profile chooses one with ``where = { instance = 0 }`` (mixing them is refused, as for
DataFlash sensor instances). Logged text messages are the pseudo-topic ``logging`` with the
field ``message`` (segment markers). Times are the log's timestamps, µs since boot. Only the
profile's topics are decoded. pyulog resynchronises after damaged bytes and stops at a
truncation; both are reported, and the part read is analysed."""

import contextlib
import io
import mmap
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from adapters.collect import ColumnSource, SignalCollector
from adapters.inventory import LogInventory, TopicInfo
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

MAGIC = b"ULog\x01\x12\x35"
INSTANCE = "instance"
LOGGING_TOPIC = "logging"
TIMESTAMP = "timestamp"
HEADER_BYTES = 16


def _load(path: Path, topics: list[str] | None, framing: "Framing") -> Any:
    """pyulog's parse of the file (only ``topics`` decoded), its errors as LogError. pyulog
    prints warnings about damaged bytes: they become notes, not terminal output."""
    from pyulog import ULog

    damaged = framing.definitions_damaged_at
    if damaged is not None:
        raise LogError(path, f"the ULog's definitions (message formats, parameters) are "
                             f"damaged at byte {damaged}: its messages cannot be decoded")

    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            return ULog(str(path), message_name_filter_list=topics,
                        disable_str_exceptions=True)
    except MemoryError:
        raise
    except Exception as error:   # pyulog raises what the bytes make it raise: wrap it
        raise LogError(path, f"not a readable ULog: {type(error).__name__}: {error}") from None


def _instances(ulog: Any) -> dict[str, list[Any]]:
    by_name: dict[str, list[Any]] = {}
    for data in ulog.data_list:
        by_name.setdefault(data.name, []).append(data)
    return by_name


def _topic_columns(instances: list[Any]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A topic's instances as one table: times (ns) and columns (fields and ``instance``)."""
    names = [n for n in instances[0].data if all(n in d.data for d in instances)]
    columns = {name: np.concatenate([d.data[name] for d in instances]) for name in names}
    columns[INSTANCE] = np.concatenate([np.full(d.data[TIMESTAMP].size, d.multi_id, np.int64)
                                        for d in instances])
    return columns[TIMESTAMP].astype(np.int64) * 1000, columns


def _column_source(columns: dict[str, np.ndarray]) -> ColumnSource:
    def column(path: str) -> np.ndarray:
        return columns[path]
    return column


class UlogAdapter:
    family = "ulog"
    formats = ("ulog",)

    def sniff(self, path: Path) -> str | None:
        if not path.is_file():
            return None
        with path.open("rb") as stream:
            return "ulog" if stream.read(len(MAGIC)) == MAGIC else None

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        collector = SignalCollector(path, sources)
        wanted = sorted(collector.topics - {LOGGING_TOPIC})
        framing = walk_framing(path)
        ulog = _load(path, wanted, framing)
        by_name = _instances(ulog)
        for topic in wanted:
            if topic in by_name:
                times_ns, columns = _topic_columns(by_name[topic])
                collector.add_columns(topic, times_ns, _column_source(columns),
                                      tuple(columns))
        if LOGGING_TOPIC in collector.topics:
            for message in ulog.logged_messages:
                collector.add(LOGGING_TOPIC, int(message.timestamp) * 1000,
                              {"message": message.message})
        _note_damage(ulog, framing, collector)
        return collector.finish("ulog", int(ulog.start_timestamp) * 1000,
                                int(ulog.last_timestamp) * 1000,
                                {name: "ULog" for name in by_name})

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        ulog = _load(path, None, walk_framing(path))
        topics = []
        for name, instances in sorted(_instances(ulog).items()):
            _, columns = _topic_columns(instances)
            ids = tuple(str(d.multi_id) for d in instances)
            topics.append(TopicInfo(name, "ULog", int(columns[TIMESTAMP].size),
                                    tuple(n for n in columns if n != TIMESTAMP),
                                    ((INSTANCE, ids),) if len(ids) > 1 else ()))
        if ulog.logged_messages:
            topics.append(TopicInfo(LOGGING_TOPIC, "ULog text", len(ulog.logged_messages),
                                    ("message",)))
        notes = [_damage_text(ulog)] if ulog.file_corruption else []
        return LogInventory("ulog", int(ulog.start_timestamp) * 1000,
                            int(ulog.last_timestamp) * 1000, topics, notes)


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


def _damage_text(ulog: Any) -> str:
    return ("damaged bytes in the ULog: pyulog skipped to the next readable message, so "
            "some messages are missing")


def _note_damage(ulog: Any, framing: Framing, collector: SignalCollector) -> None:
    if ulog.file_corruption:
        collector.notes.append(_damage_text(ulog))
        collector.damaged(_damage_text(ulog))
    cut = framing.cut_at
    if cut is not None:
        reason = f"the ULog ends inside a message at byte {cut}: the file was cut short"
        collector.notes.append(reason)
        collector.damaged(reason, cut)
    dropped_ms = sum(int(d.duration) for d in ulog.dropouts)
    if dropped_ms:
        collector.notes.append(f"the logger dropped data {len(ulog.dropouts)} time(s), "
                               f"{dropped_ms} ms in all")
