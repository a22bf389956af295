"""A ROS 1 bag read through its index: only the chunks that hold a wanted connection are
read, and in each the wanted messages are found all at once from the index data records
that follow it (time and offset of every message of a connection), as the MCAP path does
with its message indexes. Walking a chunk record by record costs microseconds a message in
Python; this costs a few array operations a chunk.

Every index entry is checked against the record it points at: the message record's header
(``op``, ``conn`` and ``time`` fields, laid out alike in every message of a chunk) must say
the same connection and time. A chunk whose index cannot be followed is walked record by
record instead; an index section that cannot be read at all raises `BagDamaged`, and the
caller salvages the bag front to back."""

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from adapters.collect import SignalCollector
from adapters.fieldnames import ros_field_paths
from adapters.inventory import LogInventory, TopicInfo
from adapters.packed import gather_words
from adapters.ros_columns import TopicBatches
from adapters.rosbag1_records import (
    MAGIC,
    OP_BAG_HEADER,
    OP_CHUNK,
    OP_CHUNK_INFO,
    OP_CONNECTION,
    OP_INDEX_DATA,
    OP_MESSAGE,
    BagDamaged,
    decompress_chunk,
    header_fields,
    number,
    opcode,
    records,
    register_connection,
    stamp_ns,
)
from adapters.signals import Signals

INDEX_ENTRY = np.dtype([("secs", "<u4"), ("nsecs", "<u4"), ("offset", "<u4")])
MESSAGE_HEADER_BYTES = 38    # op (1 byte), conn (4), time (8): three length-prefixed fields


class IndexUnusable(ValueError):
    """A chunk's index data that cannot be followed; the chunk is walked instead."""


@dataclass(frozen=True)
class BagConnection:
    topic: str
    msgtype: str                 # ROS 2 spelling, as the type store names it


@dataclass(frozen=True)
class ChunkInfo:
    position: int                # of the chunk record in the file
    start_ns: int
    end_ns: int
    counts: dict[int, int]       # messages per connection id


@dataclass
class BagIndex:
    connections: dict[int, BagConnection]
    chunks: list[ChunkInfo]
    store: Any                   # rosbags type store built from the bag's definitions
    index_position: int

    def topics(self) -> dict[str, str]:
        return {c.topic: c.msgtype for c in self.connections.values()}

    def span(self) -> tuple[int | None, int | None]:
        if not self.chunks:
            return None, None
        return min(c.start_ns for c in self.chunks), max(c.end_ns for c in self.chunks)

    def inventory(self) -> LogInventory:
        counts: dict[tuple[str, str], int] = {}
        for chunk in self.chunks:
            for conn, count in chunk.counts.items():
                if conn in self.connections:
                    key = self.connections[conn].topic, self.connections[conn].msgtype
                    counts[key] = counts.get(key, 0) + count
        for connection in self.connections.values():
            counts.setdefault((connection.topic, connection.msgtype), 0)
        topics = [TopicInfo(topic, msgtype, count, tuple(ros_field_paths(self.store, msgtype)))
                  for (topic, msgtype), count in sorted(counts.items())]
        return LogInventory("bag", *self.span(), topics)


def _read_record(stream: BinaryIO, position: int, limit: int
                 ) -> tuple[dict[str, bytes], bytes, int]:
    """The record at ``position``, which must end before ``limit``."""
    stream.seek(position)
    head = stream.read(4)
    if len(head) < 4 or position + 8 + struct.unpack("<I", head)[0] > limit:
        raise BagDamaged(f"record at byte {position} runs past its section")
    header = stream.read(struct.unpack("<I", head)[0])
    size_bytes = stream.read(4)
    data_at = position + 8 + len(header)
    if len(size_bytes) < 4 or data_at + struct.unpack("<I", size_bytes)[0] > limit:
        raise BagDamaged(f"record at byte {position} runs past its section")
    data = stream.read(struct.unpack("<I", size_bytes)[0])
    return header_fields(header), data, data_at + len(data)


def read_bag_index(stream: BinaryIO, size: int, types: bool = True) -> BagIndex:
    """The bag's connections (with their definitions registered, unless not ``types``) and
    chunk list; `BagDamaged` when the bag has no index that can be read."""
    try:
        return _read_bag_index(stream, size, types)
    except BagDamaged:
        raise
    except Exception as error:  # a definition rosbags cannot parse, a bad UTF-8 name, ...
        raise BagDamaged(f"bag index unreadable: {error}") from None


def _read_bag_index(stream: BinaryIO, size: int, types: bool) -> BagIndex:
    from rosbags.typesys import Stores, get_typestore

    stream.seek(0)
    if stream.read(len(MAGIC)) != MAGIC:
        raise BagDamaged("not a ROS 1 bag (format 2.0)")
    header, _, _ = _read_record(stream, len(MAGIC), size)
    if opcode(header) != OP_BAG_HEADER:
        raise BagDamaged("no bag header record")
    index_position = number(header, "index_pos", "<Q")
    if not len(MAGIC) < index_position < size:
        raise BagDamaged("bag is not indexed (a recording that did not finish)")
    stream.seek(index_position)
    store = get_typestore(Stores.EMPTY)
    connections: dict[int, BagConnection] = {}
    chunks: list[ChunkInfo] = []
    for record, payload in records(stream.read(size - index_position), index_position):
        kind = opcode(record)
        if kind == OP_CONNECTION:
            conn = number(record, "conn", "<I")
            connections[conn] = BagConnection(*register_connection(
                store if types else None, payload))
        elif kind == OP_CHUNK_INFO:
            chunks.append(_chunk_info(record, payload, index_position))
    return BagIndex(connections, sorted(chunks, key=lambda c: c.position), store,
                    index_position)


def _chunk_info(header: dict[str, bytes], payload: memoryview, index_position: int
                ) -> ChunkInfo:
    if number(header, "ver", "<I") != 1:
        raise BagDamaged("unsupported chunk info version")
    position, count = number(header, "chunk_pos", "<Q"), number(header, "count", "<I")
    if not len(MAGIC) < position < index_position or len(payload) != 8 * count:
        raise BagDamaged("a chunk info record does not fit the file")
    pairs = np.frombuffer(payload, "<u4").reshape(-1, 2)
    return ChunkInfo(position, stamp_ns(header.get("start_time", b"")),
                     stamp_ns(header.get("end_time", b"")),
                     dict(zip(pairs[:, 0].tolist(), pairs[:, 1].tolist(), strict=True)))


def read_indexed_bag(path: Path, collector: SignalCollector) -> Signals:
    """The profile's signals from an indexed ROS 1 bag (`BagDamaged` when it is not)."""
    with path.open("rb") as stream:
        index = read_bag_index(stream, path.stat().st_size)
        topics = index.topics()
        collector.require_topics(topics)
        wanted = {conn: c.topic for conn, c in index.connections.items()
                  if c.topic in collector.topics}
        batches = TopicBatches(collector, topics, False, index.store,
                               index.store.deserialize_ros1)

        def feed() -> None:
            for chunk in index.chunks:
                if not wanted.keys().isdisjoint(chunk.counts):
                    _read_chunk(stream, chunk, index.index_position, wanted, batches)

        batches.fill(feed)
    return collector.finish("bag", *index.span(), topics, time_ordered=True)


def _read_chunk(stream: BinaryIO, chunk: ChunkInfo, limit: int, wanted: dict[int, str],
                batches: TopicBatches) -> None:
    header, payload, after = _read_record(stream, chunk.position, limit)
    if opcode(header) != OP_CHUNK:
        raise BagDamaged(f"no chunk record at byte {chunk.position}")
    data = decompress_chunk(header, memoryview(payload))
    try:
        entries = _index_entries(stream, after, limit, chunk, wanted)
        located = {conn: _locate(np.frombuffer(data, np.uint8), conn, found)
                   for conn, found in entries.items()}
    except (IndexUnusable, BagDamaged):
        _walk_chunk(data, wanted, batches)
        return
    array = np.frombuffer(data, np.uint8)
    for conn, (times_ns, starts, ends) in located.items():
        batches.extend(wanted[conn], times_ns, array, starts, ends)


def _index_entries(stream: BinaryIO, position: int, limit: int, chunk: ChunkInfo,
                   wanted: dict[int, str]) -> dict[int, np.ndarray]:
    """The index data records after a chunk: per wanted connection, its entries."""
    entries: dict[int, np.ndarray] = {}
    for _ in chunk.counts:
        header, payload, position = _read_record(stream, position, limit)
        if opcode(header) != OP_INDEX_DATA or number(header, "ver", "<I") != 1:
            raise IndexUnusable("no index data record where the chunk's index belongs")
        conn, count = number(header, "conn", "<I"), number(header, "count", "<I")
        if len(payload) != count * INDEX_ENTRY.itemsize or chunk.counts.get(conn) != count:
            raise IndexUnusable(f"index data of connection {conn} does not fit")
        if conn in wanted:
            entries[conn] = np.frombuffer(payload, INDEX_ENTRY)
    if set(entries) != set(wanted).intersection(chunk.counts):
        raise IndexUnusable("the chunk's index leaves out a connection its info lists")
    return entries


def _locate(data: np.ndarray, conn: int, entries: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times, and where each message's data starts and ends in the chunk."""
    offsets = entries["offset"].astype(np.int64)
    times_ns = entries["secs"].astype(np.int64) * 1_000_000_000 + entries["nsecs"]
    header_end = offsets + 4 + MESSAGE_HEADER_BYTES
    if offsets.size == 0 or (header_end + 4 > data.size).any():
        raise IndexUnusable("an index entry points past its chunk")
    if (gather_words(data, offsets, "<u4") != MESSAGE_HEADER_BYTES).any():
        raise IndexUnusable("an index entry does not point at a message record")
    headers = np.lib.stride_tricks.sliding_window_view(data, MESSAGE_HEADER_BYTES)[offsets + 4]
    template = header_fields(headers[0].tobytes())
    if (opcode(template) != OP_MESSAGE or number(template, "conn", "<I") != conn
            or "time" not in template):
        raise IndexUnusable("an index entry does not point at its connection's message")
    # Every header must be the first one's bytes but for the time, which must be the index's.
    time_at = headers[0].tobytes().index(b"time=") + 5
    fixed = np.ones(MESSAGE_HEADER_BYTES, bool)
    fixed[time_at:time_at + 8] = False
    stated = gather_words(data, offsets + 4 + time_at, "<u4").astype(np.int64) * 1_000_000_000
    stated += gather_words(data, offsets + 8 + time_at, "<u4")
    if (headers[:, fixed] != headers[0, fixed]).any() or (stated != times_ns).any():
        raise IndexUnusable("an index entry does not match its message record")
    lengths = gather_words(data, header_end, "<u4").astype(np.int64)
    starts = header_end + 4
    if (starts + lengths > data.size).any():
        raise IndexUnusable("a message runs past its chunk")
    order = np.argsort(offsets, kind="stable")
    return times_ns[order], starts[order], (starts + lengths)[order]


def _walk_chunk(data: bytes, wanted: dict[int, str], batches: TopicBatches) -> None:
    for header, payload in records(data):
        if opcode(header) == OP_MESSAGE:
            topic = wanted.get(number(header, "conn", "<I"))
            if topic is not None:
                batches.append(topic, stamp_ns(header.get("time", b"")), payload)
