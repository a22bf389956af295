"""Decode every record of one message type at once into a NumPy structured array.

The payload layouts come from the libraries that define them: pymavlink's generated
message classes (their struct format, in wire order) for MAVLink, the log's own FMT
records for DataFlash. Field values equal what pymavlink's per-message decoders return
(tests/test_mavlink_columns.py holds the two side by side)."""

import re
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from adapters.fieldpath import parse_field_path
from adapters.mavlink_scan import DATAFLASH_HEADER_LENGTH, RecordIndex, tlog_frame_fields

_STRUCT_TO_NUMPY = {"b": "i1", "B": "u1", "h": "i2", "H": "u2", "i": "i4", "I": "u4",
                    "q": "i8", "Q": "u8", "f": "f4", "d": "f8", "e": "f2", "c": "S1"}
# DataFlash format characters: (numpy type, divisor pymavlink applies), see DFReader.
_DATAFLASH_TYPES: dict[str, tuple[str, float | None]] = {
    "a": ("(32,)<i2", None), "b": ("<i1", None), "B": ("<u1", None), "g": ("<f2", None),
    "h": ("<i2", None), "H": ("<u2", None), "i": ("<i4", None), "I": ("<u4", None),
    "f": ("<f4", None), "d": ("<f8", None), "n": ("S4", None), "N": ("S16", None),
    "Z": ("S64", None), "c": ("<i2", 100.0), "C": ("<u2", 100.0), "e": ("<i4", 100.0),
    "E": ("<u4", 100.0), "L": ("<i4", 1e7), "M": ("<u1", None), "q": ("<i8", None),
    "Q": ("<u8", None),
}
_STRUCT_TOKEN = re.compile(r"(\d*)([a-zA-Z?])")


class UnknownFormat(ValueError):
    """A payload layout this decoder cannot express."""


def field_column(rows: np.ndarray, path: str) -> np.ndarray:
    """A field of every decoded row: ``name``, or ``name[i]`` for element i of an array."""
    name, *rest = parse_field_path(path)
    indices = [step for step in rest if isinstance(step, int)]
    if not isinstance(name, str) or len(indices) != len(rest):
        raise ValueError(f"field path {path!r}: these messages are flat, so a path is a "
                         "field name with optional [index]")
    column = rows[name]
    for index in indices:
        column = column[:, index]
    return column


def gather_payloads(data: np.ndarray, starts: np.ndarray, lengths: np.ndarray,
                    width: int) -> np.ndarray:
    """(n, width) uint8: each payload from its start, cut or zero-padded to ``width``
    (MAVLink 2 drops trailing zero bytes on the wire; the receiver puts them back). Rows
    are copied from a sliding window over the file, so no index array of n × width."""
    rows = np.zeros((starts.size, width), np.uint8)
    if width == 0 or starts.size == 0:
        return rows
    fits = starts <= data.size - width
    if data.size >= width:
        rows[fits] = sliding_window_view(data, width)[starts[fits]]
    for row in np.flatnonzero(~fits):           # the last record or two of the file
        tail = data[starts[row]:]
        rows[row, :tail.size] = tail
    rows[np.arange(width) >= np.minimum(lengths, width)[:, None]] = 0
    return rows


def mavlink_dtype(message_class: Any) -> np.dtype:
    """The wire layout of a pymavlink message class as a packed little-endian dtype."""
    tokens = _STRUCT_TOKEN.findall(message_class.unpacker.format.lstrip("<"))
    names = message_class.ordered_fieldnames
    if len(tokens) != len(names):
        raise UnknownFormat(f"{message_class.msgname}: {message_class.unpacker.format}")
    fields: list[tuple[Any, ...]] = []
    for name, (count, code) in zip(names, tokens, strict=True):
        if code == "s":
            fields.append((name, f"S{count or 1}"))
        elif int(count or 1) > 1:
            fields.append((name, "<" + _STRUCT_TO_NUMPY[code], (int(count),)))
        else:
            fields.append((name, "<" + _STRUCT_TO_NUMPY[code]))
    dtype = np.dtype(fields)
    if dtype.itemsize != message_class.unpacker.size:
        raise UnknownFormat(f"{message_class.msgname}: {dtype.itemsize} bytes, expected "
                            f"{message_class.unpacker.size}")
    return dtype


def x25_crc(rows: np.ndarray, lengths: np.ndarray, crc_extra: int) -> np.ndarray:
    """MAVLink's CRC-16/MCRF4XX of each row's first ``lengths`` bytes, then ``crc_extra``:
    the same recurrence for every frame at once, one byte column at a time."""
    crc = np.full(rows.shape[0], 0xFFFF, np.int32)

    def feed(byte: np.ndarray | int, active: np.ndarray | slice) -> None:
        tmp = (np.asarray(byte, np.int32) ^ (crc[active] & 0xFF)) & 0xFF
        tmp = (tmp ^ (tmp << 4)) & 0xFF
        crc[active] = ((crc[active] >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)) & 0xFFFF

    for column in range(rows.shape[1]):
        active = lengths > column
        feed(rows[active, column], active)
    feed(crc_extra, slice(None))
    return crc


def decode_mavlink(index: RecordIndex, message_class: Any) -> tuple[np.ndarray, np.ndarray,
                                                                     int]:
    """Record times (µs), the decoded rows and how many frames failed their checksum."""
    positions = index.of_type(message_class.id)
    offsets = index.offsets[positions]
    version, _, starts, lengths = tlog_frame_fields(index.data, offsets)
    header = np.where(version == 2, 9, 5)             # the CRC covers the header after magic
    checked = gather_payloads(index.data, starts - header, header + lengths,
                              int((header + lengths).max(initial=0)))
    sent = gather_payloads(index.data, starts + lengths, np.full(lengths.size, 2), 2)
    valid = x25_crc(checked, header + lengths, message_class.crc_extra) == (
        sent[:, 0].astype(np.int32) | sent[:, 1].astype(np.int32) << 8)
    dtype = mavlink_dtype(message_class)
    rows = gather_payloads(index.data, starts[valid], lengths[valid], dtype.itemsize)
    return (index.times_us[positions][valid], rows.view(dtype).reshape(-1),
            int((~valid).sum()))


def dataflash_layout(types: str, columns: tuple[str, ...]
                     ) -> tuple[np.dtype, dict[str, float]]:
    """A DataFlash format as a dtype, and the divisors pymavlink applies per column."""
    if len(types) != len(columns) or any(t not in _DATAFLASH_TYPES for t in types) or len(
            set(columns)) != len(columns):
        raise UnknownFormat(f"format {types!r} for columns {','.join(columns)}")
    fields = [(name, _DATAFLASH_TYPES[t][0]) for name, t in zip(columns, types, strict=True)]
    divisors = {name: divisor for name, t in zip(columns, types, strict=True)
                if (divisor := _DATAFLASH_TYPES[t][1]) is not None}
    return np.dtype(fields), divisors


def decode_dataflash(index: RecordIndex, type_id: int
                     ) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """Record times (µs, -1 for formats without a clock: `RECORD_CLOCKS`), rows, and
    per-column divisors."""
    declared = index.formats[type_id]
    dtype, divisors = dataflash_layout(declared.types, declared.columns)
    payload = declared.length - DATAFLASH_HEADER_LENGTH
    if dtype.itemsize != payload:
        raise UnknownFormat(f"{declared.name}: format {declared.types!r} is {dtype.itemsize} "
                            f"bytes, the record {payload}")
    positions = index.of_type(type_id)
    starts = index.offsets[positions] + DATAFLASH_HEADER_LENGTH
    rows = gather_payloads(index.data, starts, np.full(starts.size, payload), payload)
    return index.times_us[positions], rows.view(dtype).reshape(-1), divisors
