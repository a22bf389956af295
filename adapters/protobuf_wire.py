"""The Protocol Buffers wire format, read from untrusted bytes: every length checked against
what is left, a varint no longer than ten bytes, no recursion of its own.

A message is a run of fields, each a key (the field's number and its wire type, a varint)
and a value: a varint (0), eight bytes (1), a length and that many bytes (2), or four bytes
(5). Groups (3, 4) were deprecated before proto3 and are refused."""

import struct
from collections.abc import Container, Iterator

VARINT, FIXED64, LENGTH_DELIMITED, FIXED32 = 0, 1, 2, 5
_MAX_VARINT_BYTES = 10
_MASK_64 = (1 << 64) - 1


class WireError(ValueError):
    """Bytes that are no Protocol Buffers message (or not the one the schema says)."""


def read_varint(data: bytes, at: int) -> tuple[int, int]:
    """The varint at ``at`` (as unsigned 64 bits) and the offset after it."""
    value = shift = 0
    for offset in range(at, min(at + _MAX_VARINT_BYTES, len(data))):
        byte = data[offset]
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value & _MASK_64, offset + 1
        shift += 7
    raise WireError("a varint runs past its message or past ten bytes")


def fields(data: bytes, kept: Container[int] | None = None
           ) -> Iterator[tuple[int, int, int | bytes]]:
    """Each field of a message: (number, wire type, value), the value an int for a varint
    and the raw bytes otherwise; with ``kept``, only the fields of those numbers (the others
    are stepped over, their bounds still checked)."""
    at, end = 0, len(data)
    while at < end:
        key = data[at]           # one byte: most keys, lengths and small values
        key, at = (key, at + 1) if key < 0x80 else read_varint(data, at)
        number, wire = key >> 3, key & 7
        if number == 0:
            raise WireError("a field numbered 0")
        if wire == VARINT:
            value, at = read_varint(data, at)
            if kept is None or number in kept:
                yield number, wire, value
            continue
        if wire == LENGTH_DELIMITED:
            size = data[at] if at < end else 0x80
            size, at = (size, at + 1) if size < 0x80 else read_varint(data, at)
        elif wire in (FIXED64, FIXED32):
            size = 8 if wire == FIXED64 else 4
        else:
            raise WireError(f"field {number} has wire type {wire} (groups are not read)")
        if size > end - at:
            raise WireError(f"field {number} runs {size - (end - at)} bytes past its message")
        if kept is None or number in kept:
            yield number, wire, data[at:at + size]
        at += size


def signed(value: int, bits: int = 64) -> int:
    """A varint read as a two's complement integer of ``bits``."""
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >> (bits - 1) else value


def zigzag(value: int) -> int:
    """A sint32 / sint64 varint decoded."""
    return (value >> 1) ^ -(value & 1)


def packed_varints(data: bytes) -> Iterator[int]:
    at = 0
    while at < len(data):
        value, at = read_varint(data, at)
        yield value


def packed_fixed(data: bytes, code: str) -> tuple[int | float, ...]:
    """Packed fixed-size values (struct ``code``: d, f, q, Q, i, I)."""
    size = struct.calcsize(code)
    if len(data) % size:
        raise WireError(f"packed values of {size} bytes in {len(data)} bytes")
    return struct.unpack(f"<{len(data) // size}{code}", data)
