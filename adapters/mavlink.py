"""MAVLink telemetry logs (.tlog) and ArduPilot DataFlash logs (.bin).

The records are walked once (`adapters.mavlink_scan`) and only the message types the
profile names are decoded, each type all at once (`adapters.mavlink_columns`), with
pymavlink's message definitions for MAVLink and the log's FMT records for DataFlash. A
tlog's times are the ground station's receive times; a DataFlash log's are the autopilot's
TimeUS (µs since boot; TimeMS, ms, in logs of ArduPilot 3.2 and before)."""

from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from adapters.autopilot_messages import dataflash_messages, tlog_messages
from adapters.collect import SignalCollector
from adapters.extractor import INSTANCE_FIELDS, ColumnSource
from adapters.fieldpath import parse_field_path
from adapters.inventory import LogInventory, TopicInfo
from adapters.mavlink_columns import (
    UnknownFormat,
    decode_dataflash,
    decode_mavlink,
    field_column,
)
from adapters.mavlink_scan import NO_TIME, RecordIndex, index_file
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError


class TlogAdapter:
    family = "mavlink"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        collector = SignalCollector(path, sources)
        index = index_file(path, "tlog", _message_names())
        classes = _message_classes()
        dropped = 0
        for topic in sorted(collector.topics):
            message_class = classes.get(topic)
            if message_class is None:
                continue           # not in the dialect: finish() names the signal
            try:
                times_us, rows, failed = decode_mavlink(index, message_class)
            except UnknownFormat as error:
                raise LogError(path, f"cannot decode {topic}: {error}") from None
            dropped += failed
            _add_timed(collector, topic, times_us, rows, {})
        if dropped:
            collector.notes.append(f"{dropped} MAVLink frames failed their checksum and were "
                                   "left out")
        first_us = index.span_us[0]
        signals = _finish(collector, "tlog", None if first_us is None else first_us * 1000,
                          index, "MAVLink")
        signals.autopilot_messages = tlog_messages(index)
        return signals

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        return _inventory("tlog", index_file(path, "tlog", _message_names()), "MAVLink")


class DataflashAdapter:
    family = "dataflash"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        collector = SignalCollector(path, sources)
        index = index_file(path, "bin")
        type_ids = {declared.name: type_id for type_id, declared in index.formats.items()}
        for topic in sorted(collector.topics & type_ids.keys()):
            try:
                times_us, rows, divisors = decode_dataflash(index, type_ids[topic])
            except UnknownFormat as error:
                raise LogError(path, f"cannot decode {topic}: {error}") from None
            if rows.size and (times_us == NO_TIME).all():
                raise LogError(path, f"{topic} records carry no TimeUS (or TimeMS), so they "
                                     "cannot be placed in time")
            _add_timed(collector, topic, times_us, rows, divisors)
        signals = _finish(collector, "bin", None, index, "DataFlash")
        signals.autopilot_messages = dataflash_messages(index)
        return signals

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        return _inventory("bin", index_file(path, "bin"), "DataFlash")


def _add_timed(collector: SignalCollector, topic: str, times_us: np.ndarray, rows: np.ndarray,
               divisors: dict[str, float]) -> None:
    """Hand one message type's rows to the collector, without those whose time is corrupt."""
    timed = times_us >= 0
    if not timed.all():
        collector.notes.append(f"{topic}: {int((~timed).sum())} record(s) with an impossible "
                               "time left out")
        times_us, rows = times_us[timed], rows[timed]
    collector.add_columns(topic, times_us * 1000, _columns_of(rows, divisors),
                          rows.dtype.names or ())


def _columns_of(rows: np.ndarray, divisors: dict[str, float]) -> ColumnSource:
    """Field paths on decoded rows; DataFlash's scaled integer columns divided back."""
    def column(path: str) -> np.ndarray:
        name = str(parse_field_path(path)[0])
        values = field_column(rows, path)
        return values / divisors[name] if name in divisors else values

    return column


def _finish(collector: SignalCollector, fmt: str, start_ns: int | None, scan: RecordIndex,
            kind: str) -> Signals:
    """The record walk names the message types and says where the file breaks, if it does."""
    if scan.problem:
        collector.notes.append(scan.problem.reason)
        collector.damaged(scan.problem.reason, scan.problem.at_byte)
    return collector.finish(fmt, start_ns, None, {name: kind for name in scan.counts})


@cache
def _message_classes() -> dict[str, Any]:
    """pymavlink's generated message classes (ArduPilot dialect, a superset of common)."""
    from pymavlink.dialects.v20 import ardupilotmega

    return {cls.msgname: cls for cls in ardupilotmega.mavlink_map.values()}


def _message_names() -> dict[int, str]:
    return {cls.id: name for name, cls in _message_classes().items()}


def _inventory(fmt: str, scan: RecordIndex, kind: str) -> LogInventory:
    first_us, last_us = scan.span_us
    described = [_topic_info(scan, fmt, kind, name, count)
                 for name, count in sorted(scan.counts.items())]
    notes = [scan.problem.reason] if scan.problem else []
    failed = {topic.name: n for topic, n in described if n}
    if failed:
        notes.append(f"{sum(failed.values())} MAVLink frames fail their checksum in the "
                     "dialect this tool reads (counted "
                     "above; a diagnosis leaves them out): "
                     + ", ".join(f"{name} {n}" for name, n in failed.items()))
    return LogInventory(fmt, None if first_us is None else first_us * 1000,
                        None if last_us is None else last_us * 1000,
                        [topic for topic, _ in described], notes,
                        tlog_messages(scan) if fmt == "tlog" else dataflash_messages(scan))


def _topic_info(scan: RecordIndex, fmt: str, kind: str, name: str, count: int
                ) -> tuple[TopicInfo, int]:
    """A message type's fields, with the values of its instance key or NAMED_VALUE name,
    and how many of its records fail their checksum."""
    try:
        if fmt == "tlog":
            message_class = _message_classes().get(name)
            if message_class is None:
                return TopicInfo(name, kind, count), 0
            _, rows, failed = decode_mavlink(scan, message_class)
        else:
            type_id = next(t for t, f in scan.formats.items() if f.name == name)
            _, rows, _ = decode_dataflash(scan, type_id)
            failed = 0                # DataFlash records carry no checksum
    except (StopIteration, UnknownFormat, ValueError):   # a layout this reader cannot show
        return TopicInfo(name, kind, count), 0
    fields = tuple(rows.dtype.names or ())
    instances = tuple((key, _distinct(rows[key])) for key in INSTANCE_FIELDS if key in fields)
    names = _distinct(rows["name"]) if name.startswith("NAMED_VALUE") else ()
    return TopicInfo(name, kind, count, fields, instances, names), failed


def _distinct(column: np.ndarray) -> tuple[str, ...]:
    values = [v.split(b"\0", 1)[0].decode("utf-8", "replace") if isinstance(v, bytes)
              else str(v) for v in np.unique(column).tolist()]
    return tuple(values)
