"""PX4 ULog files (.ulg), packed here to the ULog specification (pyulog reads them back; its
own writer rewrites logs it has read and cannot start one). A file is the 16-byte header
(``ULog`` magic, version, start time in µs since boot), the flag bits, one format per topic,
then topic subscriptions and data messages in time order; every message is ``<size u16>
<type u8> <payload>``, little-endian."""

import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adapters.fieldpath import parse_field_path
from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import dive_records, family_sources, operating_records
from auvdiag_cli.vehicle.profile import Profile

MAGIC = b"ULog\x01\x12\x35"
VERSION = 1
INFO_LEVEL = ord("6")
# A PX4 log's clock counts from boot; the logger starts a little after it.
BOOT_BEFORE_LOG_US = 5_000_000
INSTANCE_KEY = "instance"      # `where = { instance = N }` is the topic's multi-instance id


@dataclass(frozen=True)
class UlogTopic:
    """One topic instance: its float fields (array fields as ``name[i]``) sampled at
    ``times_us`` (µs since boot), one column per field."""

    name: str
    fields: tuple[str, ...]
    times_us: np.ndarray
    columns: np.ndarray                   # (samples, fields)
    instance: int = 0


def _message(kind: str, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def _layout(fields: Sequence[str]) -> tuple[str, list[int], int]:
    """The format text, where each field sits among the floats after the timestamp, and how
    many floats there are: ``xyz[2]`` and ``xyz[0]`` make one ``float[3] xyz``."""
    steps = [parse_field_path(path) for path in fields]
    sizes: dict[str, int] = {}
    for step in steps:
        index = int(step[1]) + 1 if len(step) > 1 else 0
        sizes[str(step[0])] = max(sizes.get(str(step[0]), 0), index)
    starts, width = {}, 0
    for name, size in sizes.items():
        starts[name] = width
        width += max(size, 1)
    text = "".join(f"float[{size}] {name};" if size else f"float {name};"
                   for name, size in sizes.items())
    slots = [starts[str(step[0])] + (int(step[1]) if len(step) > 1 else 0) for step in steps]
    return "uint64_t timestamp;" + text, slots, width


def write_ulog_file(path: Path, topics: Sequence[UlogTopic], start_us: int,
                    texts: Sequence[tuple[int, str]] = (), system: str = "PX4",
                    info: Mapping[str, str] | None = None) -> None:
    """Write ``topics`` (and logged text messages ``(time_us, text)``) as a ULog file, its
    information messages ``sys_name`` = ``system`` and ``info``."""
    parts = [MAGIC + bytes([VERSION]) + struct.pack("<Q", start_us),
             _message("B", bytes(40))]
    for name, value in {"sys_name": system, **(info or {})}.items():
        key = f"char[{len(value)}] {name}".encode()
        parts.append(_message("I", bytes([len(key)]) + key + value.encode()))
    formats: dict[str, tuple[str, list[int], int]] = {}
    for topic in topics:
        layout = _layout(topic.fields)
        if formats.setdefault(topic.name, layout)[0] != layout[0]:
            raise ValueError(f"instances of {topic.name} differ in their fields")
    parts += [_message("F", f"{name}:{text}".encode()) for name, (text, _, _) in formats.items()]
    timed: list[tuple[int, int, bytes]] = []
    for msg_id, topic in enumerate(topics):
        parts.append(_message("A", struct.pack("<BH", topic.instance, msg_id)
                              + topic.name.encode()))
        _, slots, width = formats[topic.name]
        row = struct.Struct(f"<HQ{width}f")
        values = np.zeros((topic.times_us.size, width))
        for column, slot in enumerate(slots):
            values[:, slot] = topic.columns[:, column]
        for time_us, sample in zip(topic.times_us.tolist(), values.tolist(), strict=True):
            timed.append((time_us, msg_id, _message("D", row.pack(msg_id, time_us, *sample))))
    for time_us, text in texts:
        timed.append((time_us, -1, _message("L", struct.pack("<BQ", INFO_LEVEL, time_us)
                                            + text.encode())))
    timed.sort(key=lambda item: (item[0], item[1]))
    with path.open("wb") as stream:
        stream.write(b"".join(parts))
        stream.write(b"".join(message for _, _, message in timed))


def write_ulog(dive: SimulatedDive, profile: Profile, path: Path) -> None:
    """The dive as the profile's `[sources.ulog]` says the vehicle logs it; segment markers
    as logged text messages."""
    sources = family_sources(profile, "ulog")
    boot_ns = dive.start_ns - BOOT_BEFORE_LOG_US * 1000
    grouped: dict[tuple[str, int], dict[str, list[float]]] = {}
    times: dict[tuple[str, int], list[int]] = {}
    texts: list[tuple[int, str]] = []
    records = [*dive_records(dive, profile, "ulog"), *operating_records(dive, profile, "ulog")]
    for record in sorted(records, key=lambda record: record.time_ns):
        time_us = (record.time_ns - boot_ns) // 1000
        if record.text is not None:
            texts.append((time_us, record.text[1]))
            continue
        where = dict(record.where)
        key = (record.topic, int(where.get(INSTANCE_KEY, 0)))
        columns = grouped.setdefault(key, {})
        times.setdefault(key, []).append(time_us)
        for field, value in record.fields:
            columns.setdefault(field, []).append(float(value))
    if sources.segment is not None and sources.segment.topic != "logging":
        raise ValueError("ULog segment markers are logged text messages: "
                         "segment = { message = \"logging\", field = \"message\" }")
    topics = [UlogTopic(name, tuple(columns), np.asarray(times[name, instance], np.int64),
                        np.column_stack([columns[f] for f in columns]), instance)
              for (name, instance), columns in grouped.items()]
    write_ulog_file(path, topics, int(min(t.times_us[0] for t in topics)), texts)
