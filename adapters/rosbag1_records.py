"""The record layer of a ROS 1 bag (format 2.0), shared by the indexed reader and the
record-by-record salvage: every record is a header (``name=value`` fields, each preceded
by its length) and a data block, both preceded by their length. Lengths are untrusted and
checked against the bytes that remain before anything is sliced or allocated."""

import bz2
import struct
from collections.abc import Iterator
from typing import Any

from adapters.limits import MAX_CHUNK_BYTES

MAGIC = b"#ROSBAG V2.0\n"
OP_MESSAGE, OP_BAG_HEADER, OP_INDEX_DATA = 0x02, 0x03, 0x04
OP_CHUNK, OP_CHUNK_INFO, OP_CONNECTION = 0x05, 0x06, 0x07


class BagDamaged(Exception):
    """A record that is incomplete or does not say what its kind must say."""


def header_fields(buffer: bytes | memoryview) -> dict[str, bytes]:
    fields, position = {}, 0
    while position + 4 <= len(buffer):
        (length,) = struct.unpack_from("<I", buffer, position)
        name, _, value = bytes(buffer[position + 4:position + 4 + length]).partition(b"=")
        fields[name.decode("ascii", "replace")] = value
        position += 4 + length
    return fields


def record_at(view: memoryview, position: int, base: int = 0
              ) -> tuple[dict[str, bytes], memoryview, int]:
    """The record at ``position`` of ``view``: its header fields, its data, and where the
    next record starts. ``base`` is the view's offset in the file, for messages."""
    if position + 4 > len(view):
        raise BagDamaged(f"record header cut at byte {base + position}")
    (header_length,) = struct.unpack_from("<I", view, position)
    data_at = position + 4 + header_length + 4
    if data_at > len(view):
        raise BagDamaged(f"record cut at byte {base + position}")
    header = header_fields(view[position + 4:data_at - 4])
    (data_length,) = struct.unpack_from("<I", view, data_at - 4)
    if data_at + data_length > len(view):
        raise BagDamaged(f"record data cut at byte {base + position}")
    return header, view[data_at:data_at + data_length], data_at + data_length


def records(data: bytes | memoryview, base: int = 0
            ) -> Iterator[tuple[dict[str, bytes], memoryview]]:
    """Every record of ``data`` in order."""
    view, position = memoryview(data), 0
    while position < len(view):
        header, payload, position = record_at(view, position, base)
        yield header, payload


def opcode(header: dict[str, bytes]) -> int:
    return header.get("op", b"\0")[:1].ljust(1, b"\0")[0]


def number(header: dict[str, bytes], name: str, fmt: str) -> int:
    """A fixed-size number field of a header; a missing or short one is damage."""
    value = header.get(name, b"")
    if len(value) != struct.calcsize(fmt):
        raise BagDamaged(f"record field {name!r} missing or malformed")
    return int(struct.unpack(fmt, value)[0])


def stamp_ns(value: bytes) -> int:
    """A ROS 1 time (seconds, nanoseconds) in nanoseconds."""
    if len(value) != 8:
        raise BagDamaged("a time field is not 8 bytes")
    secs, nsecs = struct.unpack("<II", value)
    return secs * 1_000_000_000 + nsecs


def decompress_chunk(header: dict[str, bytes], payload: memoryview) -> bytes:
    """A chunk's records, never more than the size its header declares (itself capped)."""
    compression = header.get("compression", b"none")
    size = number(header, "size", "<I")
    if size > MAX_CHUNK_BYTES:
        raise BagDamaged(f"a chunk declares {size} bytes uncompressed")
    if compression == b"none":
        return bytes(payload)
    if compression == b"bz2":
        return bz2.BZ2Decompressor().decompress(payload, max_length=size)
    if compression == b"lz4":
        import lz4.frame

        return bytes(lz4.frame.LZ4FrameDecompressor().decompress(bytes(payload),
                                                                 max_length=size))
    raise BagDamaged(f"unknown chunk compression {compression[:20]!r}")


def register_connection(store: Any, payload: memoryview) -> tuple[str, str]:
    """Register the message definition a connection record carries in ``store`` (None:
    only name it); its topic and its message type in ROS 2 spelling (``pkg/msg/Type``)."""
    from rosbags.typesys import get_types_from_msg

    fields = header_fields(payload)
    if "type" not in fields or "topic" not in fields:
        raise BagDamaged("a connection record without topic or type")
    msgtype = fields["type"].decode("utf-8", "replace")
    if store is not None:
        store.register(get_types_from_msg(
            fields.get("message_definition", b"").decode("utf-8", "replace"), msgtype))
    name = msgtype if "/msg/" in msgtype else msgtype.replace("/", "/msg/", 1)
    return fields["topic"].decode("utf-8", "replace"), name
