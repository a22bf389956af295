"""Read a ROS 1 bag front to back without its index: what a killed recorder leaves
(``.bag.active``, index_pos = 0) or a truncated copy. rosbags refuses such files; the records
themselves are intact up to the damage, so they are walked one by one until the first record
that is incomplete. The chunk the damage falls in is lost whole."""

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from adapters.collect import SignalCollector
from adapters.rosbag1_records import (
    MAGIC,
    OP_CHUNK,
    OP_CONNECTION,
    OP_MESSAGE,
    BagDamaged,
    decompress_chunk,
    opcode,
    records,
    register_connection,
    stamp_ns,
)


@dataclass(frozen=True)
class _Connection:
    topic: str
    msgtype: str


class _Decoder:
    """Builds a type store from the definitions the bag's connection records carry."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.EMPTY)
        self.connections: dict[int, _Connection] = {}
        self.counts: dict[str, int] = {}                 # messages per topic

    def connection(self, header: dict[str, bytes], payload: memoryview) -> None:
        (conn,) = struct.unpack("<I", header["conn"])
        self.connections[conn] = _Connection(*register_connection(self.store, payload))

    def message(self, header: dict[str, bytes], payload: memoryview, collector: SignalCollector,
                topics: dict[str, str]) -> None:
        (conn,) = struct.unpack("<I", header["conn"])
        connection = self.connections.get(conn)
        if connection is None:
            return
        topics[connection.topic] = connection.msgtype
        self.counts[connection.topic] = self.counts.get(connection.topic, 0) + 1
        if collector.wants(connection.topic):
            decoded: Any = self.store.deserialize_ros1(bytes(payload), connection.msgtype)
            collector.add(connection.topic, stamp_ns(header["time"]), decoded)


def _walk(view: bytes | memoryview, decoder: _Decoder, collector: SignalCollector,
          topics: dict[str, str], inside_chunk: bool = False) -> None:
    for header, payload in records(view, 0 if inside_chunk else len(MAGIC)):
        op = opcode(header)
        if op == OP_CONNECTION:
            decoder.connection(header, payload)
        elif op == OP_MESSAGE:
            decoder.message(header, payload, collector, topics)
        elif op == OP_CHUNK and not inside_chunk:
            _walk(decompress_chunk(header, payload), decoder, collector, topics, inside_chunk=True)


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
            raise BagDamaged("not a ROS 1 bag")
        _walk(memoryview(data)[len(MAGIC):], decoder, collector, topics)
    except BagDamaged as error:
        stopped = str(error)
    except Exception as error:  # a damaged chunk fails inside lz4/bz2 or the decoder
        stopped = f"{type(error).__name__}: {error}"
    return SalvagedBag(topics, decoder.counts, stopped)
