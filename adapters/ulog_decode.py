"""A columnar ULog decoder: one walk over the message headers, then every wanted topic's
data messages decoded at once with NumPy, each subscription's packed format as a
structured dtype. Fields are named as pyulog names them (nested types flattened with
``.``, arrays as ``[i]``, trailing padding dropped), so profiles and pyulog agree.

Damage is handled the way pyulog handles it, without its byte-by-byte retries: a data
message of another size than its format's (trailing padding is not logged), or of an id
nothing subscribed, is skipped and marks the log corrupt; a header that cannot be a
message (type or size 0, or an unknown type larger than any message) resynchronises at the
next sync marker, and the walk stops where none is left; a message cut by the end of the
file ends the walk there. Logs with appended data (a flag
that sends the reader to offsets after a crash) raise `AppendedData`."""

import struct
from array import array
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from adapters.packed import gather_words
from adapters.recognise import ULOG_MAGIC

SYNC = b"\x2f\x73\x13\x20\x25\x0c\xbb\x12"
HEADER_BYTES = 16
TYPES = {"int8_t": "<i1", "uint8_t": "<u1", "int16_t": "<i2", "uint16_t": "<u2",
         "int32_t": "<i4", "uint32_t": "<u4", "int64_t": "<i8", "uint64_t": "<u8",
         "float": "<f4", "double": "<f8", "bool": "<i1", "char": "<i1"}
DEFINITIONS = frozenset(b"BFIMPQ")
KNOWN = frozenset(b"ABCDFILMOPQRS")
LARGEST_MESSAGE = 10_000       # an unknown type this large is damage, not a new message
MAX_NESTING = 16
TIMESTAMP = "timestamp"
_HEAD = struct.Struct("<HB")


class AppendedData(Exception):
    """The log continues at appended offsets; the caller reads it another way."""


class DefinitionsDamaged(ValueError):
    """The definitions (formats, parameters) are damaged at byte ``at``."""

    def __init__(self, at: int) -> None:
        super().__init__(f"definitions damaged at byte {at}")
        self.at = at


@dataclass
class Instance:
    multi_id: int
    columns: dict[str, np.ndarray]        # field name → values; "timestamp" in µs


@dataclass
class DecodedUlog:
    start_us: int
    topics: dict[str, list[Instance]] = field(default_factory=dict)
    logged: list[tuple[int, str, int]] = field(default_factory=list)   # (µs, text, level)
    dropouts_ms: list[int] = field(default_factory=list)
    corrupt: bool = False          # messages were skipped
    cut_at: int | None = None      # the file ends inside the message starting here
    last_us: int = 0


def _text(raw: bytes | memoryview) -> str:
    return bytes(raw).decode("utf-8", "ignore")


def _format(payload: bytes) -> tuple[str, list[tuple[str, int, str]]]:
    """A format message: its name and its fields as (type, array length or 0, name)."""
    name, _, body = _text(payload).partition(":")
    fields = []
    for item in filter(None, body.split(";")):
        kind, _, field_name = item.strip().partition(" ")
        size = 0
        if "[" in kind:
            kind, _, count = kind.partition("[")
            size = int(count.rstrip("]"))
        fields.append((kind, size, field_name))
    return name, fields


def _flatten(formats: dict[str, list[tuple[str, int, str]]], name: str, prefix: str = "",
             depth: int = 0) -> list[tuple[str, str]]:
    if depth > MAX_NESTING:
        raise ValueError(f"format {name} nests too deep")
    flat: list[tuple[str, str]] = []
    for kind, size, field_name in formats[name]:
        names = [f"{prefix}{field_name}[{i}]" for i in range(size)] if size else [
            f"{prefix}{field_name}"]
        for each in names:
            if kind in TYPES:
                flat.append((each, TYPES[kind]))
            else:
                flat += _flatten(formats, kind, f"{each}.", depth + 1)
    return flat


@dataclass
class _Subscription:
    name: str
    multi_id: int
    dtype: np.dtype                # without trailing padding, which PX4 does not log


def _subscription(formats: dict[str, Any], payload: bytes) -> tuple[int, _Subscription | None]:
    multi_id, msg_id = struct.unpack_from("<BH", payload)
    name = _text(payload[3:]).rstrip("\0")
    try:
        flat = _flatten(formats, name)
        while flat and flat[-1][0].split(".")[-1].startswith("_padding"):
            flat.pop()
        dtype = np.dtype(flat)
    except (KeyError, ValueError, TypeError):   # no or a malformed format: undecodable
        return msg_id, None
    return msg_id, _Subscription(name, multi_id, dtype)


def _definitions(data: Any, size: int) -> tuple[int, dict[str, Any]]:
    """Where the data section starts, and the message formats."""
    at = HEADER_BYTES
    formats: dict[str, list[tuple[str, int, str]]] = {}
    while at + 3 <= size:
        length, kind = _HEAD.unpack_from(data, at)
        end = at + 3 + length
        if kind in b"ALC":
            return at, formats
        if kind == 0 or length == 0 or end > size or kind not in DEFINITIONS:
            raise DefinitionsDamaged(at)
        if kind == ord("B") and length >= 16:
            incompatible = data[at + 3 + 8:at + 3 + 16]
            if incompatible[0] & 1:
                raise AppendedData("the log has appended data")
            if incompatible[0] & ~1 or any(incompatible[1:]):
                raise ValueError("the log sets incompatibility flags this reader does not know")
        elif kind == ord("F"):
            try:
                name, fields = _format(bytes(data[at + 3:end]))
            except ValueError:          # an array length that is not a number
                raise DefinitionsDamaged(at) from None
            formats[name] = fields
        at = end
    raise DefinitionsDamaged(at)


def decode_ulog(data: Any, wanted: set[str] | None) -> DecodedUlog:
    """Decode ``data`` (the whole file's bytes); only topics in ``wanted`` (None: all)."""
    size = len(data)
    if size < HEADER_BYTES or bytes(data[:len(ULOG_MAGIC)]) != ULOG_MAGIC:
        raise ValueError("not a ULog file")
    decoded = DecodedUlog(struct.unpack_from("<Q", data, 8)[0])
    at, formats = _definitions(data, size)
    subscriptions: dict[int, _Subscription | None] = {}
    messages = array("q")                       # where each data message starts
    keep = messages.append
    while at + 3 <= size:
        length, kind = _HEAD.unpack_from(data, at)
        end = at + 3 + length
        if end > size:
            decoded.cut_at = at
            break
        if kind == 68:                                                  # D
            keep(at)
        elif kind == 0 or length == 0 or (kind not in KNOWN and length > LARGEST_MESSAGE):
            decoded.corrupt = True
            found = data.find(SYNC, at + 1)
            if found < 0:
                at = size                       # nothing after this can be trusted
                break
            end = found + len(SYNC)
        elif kind == 65 and length >= 3:                                # A
            msg_id, subscription = _subscription(formats, bytes(data[at + 3:end]))
            subscriptions[msg_id] = subscription
        elif kind == 76 and length >= 9:                                # L
            decoded.logged.append((struct.unpack_from("<Q", data, at + 4)[0],
                                   _text(data[at + 12:end]), data[at + 3]))
        elif kind == 79 and length >= 2:                                # O
            decoded.dropouts_ms.append(struct.unpack_from("<H", data, at + 3)[0])
        at = end
    if decoded.cut_at is None and at < size:    # the file ends inside a message header
        decoded.cut_at = at
    _decode_data(np.frombuffer(data, np.uint8), np.frombuffer(messages, np.int64),
                 subscriptions, wanted, decoded)
    return decoded


def _decode_data(raw: np.ndarray, starts: np.ndarray,
                 subscriptions: dict[int, "_Subscription | None"], wanted: set[str] | None,
                 decoded: DecodedUlog) -> None:
    payloads = gather_words(raw, starts, "<u2").astype(np.int64) - 2
    readable = payloads >= 0
    decoded.corrupt |= not readable.all()
    starts, payloads = starts[readable], payloads[readable]
    ids = gather_words(raw, starts + 3, "<u2")
    decoded.corrupt |= not np.isin(ids, list(subscriptions)).all()
    for msg_id, subscription in subscriptions.items():
        if subscription is None or (wanted is not None and subscription.name not in wanted):
            continue
        mine = ids == msg_id
        fits = payloads == subscription.dtype.itemsize
        decoded.corrupt |= bool((mine & ~fits).any())
        chosen = starts[mine & fits] + 5
        names = subscription.dtype.names or ()
        if chosen.size == 0 or TIMESTAMP not in names:
            continue
        width = subscription.dtype.itemsize
        rows = np.lib.stride_tricks.sliding_window_view(raw, width)[chosen]
        records = np.ascontiguousarray(rows).view(subscription.dtype)[:, 0]
        columns = {name: np.ascontiguousarray(records[name])
                   for name in names}
        decoded.topics.setdefault(subscription.name, []).append(
            Instance(subscription.multi_id, columns))
        decoded.last_us = max(decoded.last_us, int(columns[TIMESTAMP].max()))
