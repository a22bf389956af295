"""Read a ROS 1 bag front to back without its index: what a killed recorder leaves
(``.bag.active``, index_pos = 0) or a truncated copy. rosbags refuses such files; the records
themselves are intact up to the damage, so they are walked one by one until the first record
that is incomplete. The chunk the damage falls in is lost whole."""

import bz2
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from adapters.collect import SignalCollector
from adapters.limits import MAX_CHUNK_BYTES

MAGIC = b"#ROSBAG V2.0\n"
OP_MESSAGE, OP_CHUNK, OP_CONNECTION = 0x02, 0x05, 0x07


class _Damaged(Exception):
    """The walk reached an incomplete or undecodable record."""


@dataclass(frozen=True)
class _Connection:
    topic: str
    msgtype: str


def _fields(buffer: bytes) -> dict[str, bytes]:
    fields, position = {}, 0
    while position + 4 <= len(buffer):
        (length,) = struct.unpack_from("<I", buffer, position)
        name, _, value = buffer[position + 4:position + 4 + length].partition(b"=")
        fields[name.decode("ascii", "replace")] = value
        position += 4 + length
    return fields


def _records(data: bytes | memoryview, base: int = 0
             ) -> Iterator[tuple[dict[str, bytes], memoryview]]:
    """Records of ``data``; ``base`` is its offset in the file, for messages."""
    view, position = memoryview(data), 0
    while position < len(view):
        if position + 4 > len(view):
            raise _Damaged(f"record header cut at byte {base + position}")
        (header_length,) = struct.unpack_from("<I", view, position)
        data_at = position + 4 + header_length + 4
        if data_at > len(view):
            raise _Damaged(f"record cut at byte {base + position}")
        header = _fields(bytes(view[position + 4:data_at - 4]))
        (data_length,) = struct.unpack_from("<I", view, data_at - 4)
        if data_at + data_length > len(view):
            raise _Damaged(f"record data cut at byte {base + position}")
        yield header, view[data_at:data_at + data_length]
        position = data_at + data_length


def _decompress(header: dict[str, bytes], payload: memoryview) -> bytes:
    """A chunk's records, never more than the size its header declares (itself capped)."""
    compression = header.get("compression", b"none")
    (size,) = struct.unpack("<I", header.get("size", b"\0\0\0\0")[:4].ljust(4, b"\0"))
    if size > MAX_CHUNK_BYTES:
        raise _Damaged(f"a chunk declares {size} bytes uncompressed")
    if compression == b"none":
        return bytes(payload)
    if compression == b"bz2":
        return bz2.BZ2Decompressor().decompress(payload, max_length=size)
    if compression == b"lz4":
        import lz4.frame

        return bytes(lz4.frame.LZ4FrameDecompressor().decompress(bytes(payload),
                                                                 max_length=size))
    raise _Damaged(f"unknown chunk compression {compression[:20]!r}")


class _Decoder:
    """Builds a type store from the definitions the bag's connection records carry."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.EMPTY)
        self.connections: dict[int, _Connection] = {}
        self.counts: dict[str, int] = {}                 # messages per topic

    def connection(self, header: dict[str, bytes], payload: memoryview) -> None:
        from rosbags.typesys import get_types_from_msg

        fields = _fields(bytes(payload))
        msgtype = fields["type"].decode()
        types = get_types_from_msg(fields["message_definition"].decode(), msgtype)
        self.store.register(types)
        (conn,) = struct.unpack("<I", header["conn"])
        name = msgtype if "/msg/" in msgtype else msgtype.replace("/", "/msg/", 1)
        self.connections[conn] = _Connection(header["topic"].decode(), name)

    def message(self, header: dict[str, bytes], payload: memoryview, collector: SignalCollector,
                topics: dict[str, str]) -> None:
        (conn,) = struct.unpack("<I", header["conn"])
        connection = self.connections.get(conn)
        if connection is None:
            return
        topics[connection.topic] = connection.msgtype
        self.counts[connection.topic] = self.counts.get(connection.topic, 0) + 1
        if connection.topic in collector.topics:
            secs, nsecs = struct.unpack("<II", header["time"])
            decoded: Any = self.store.deserialize_ros1(bytes(payload), connection.msgtype)
            collector.add(connection.topic, secs * 1_000_000_000 + nsecs, decoded)


def _walk(view: bytes | memoryview, decoder: _Decoder, collector: SignalCollector,
          topics: dict[str, str], inside_chunk: bool = False) -> None:
    for header, payload in _records(view, 0 if inside_chunk else len(MAGIC)):
        op = header.get("op", b"\0")[0]
        if op == OP_CONNECTION:
            decoder.connection(header, payload)
        elif op == OP_MESSAGE:
            decoder.message(header, payload, collector, topics)
        elif op == OP_CHUNK and not inside_chunk:
            _walk(_decompress(header, payload), decoder, collector, topics, inside_chunk=True)


@dataclass
class SalvagedBag:
    topics: dict[str, str]           # topic → message type, of every message read
    counts: dict[str, int]           # messages per topic
    stopped: str | None              # where and why the walk stopped (None: the whole file)


def salvage_bag1(path: Path, collector: SignalCollector) -> SalvagedBag:
    """Feed every readable message to ``collector``; say what was seen and where the walk
    stopped."""
    data = path.read_bytes()
    decoder = _Decoder()
    topics: dict[str, str] = {}
    stopped: str | None = None
    try:
        if not data.startswith(MAGIC):
            raise _Damaged("not a ROS 1 bag")
        _walk(memoryview(data)[len(MAGIC):], decoder, collector, topics)
    except _Damaged as error:
        stopped = str(error)
    except Exception as error:  # a damaged chunk fails inside lz4/bz2 or the decoder
        stopped = f"{type(error).__name__}: {error}"
    return SalvagedBag(topics, decoder.counts, stopped)
