"""ROS 1 bags read through their index against the same bags walked record by record (the
salvage reader, which trusts no index) and against rosbags' own reader: same samples, same
times, same counts; a chunk whose index is damaged is walked instead, with the same result."""

from pathlib import Path

import pytest
from helpers import assert_same_signals
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_typestore

from adapters import inventory, read_log, rosbag1_index
from adapters.collect import SignalCollector
from adapters.rosbag import RosbagAdapter
from adapters.rosbag1_index import _walk_chunk as walk_chunk
from adapters.rosbag1_index import read_bag_index
from adapters.rosbag1_records import record_at

UNCOMPRESSED = None


def rewrite(source: Path, target: Path, compression: object, chunk_bytes: int) -> None:
    """The messages of ``source`` again, with another compression and chunk size, and the
    thruster topic split over two connections (two publishers, as a real system has)."""
    store = get_typestore(Stores.ROS1_NOETIC)
    writer = Writer(target)
    if compression is not None:
        writer.set_compression(compression)  # type: ignore[arg-type]
    writer.chunk_threshold = chunk_bytes
    with AnyReader([source]) as reader, writer:
        connections = {}
        for connection in reader.connections:
            connections[connection.id] = [
                writer.add_connection(connection.topic, connection.msgtype, typestore=store,
                                      callerid=f"/node{copy}")
                for copy in range(2 if "thruster" in connection.topic else 1)]
        for index, (connection, time_ns, raw) in enumerate(reader.messages()):
            copies = connections[connection.id]
            writer.write(copies[index % len(copies)], time_ns, raw)


def walked(path: Path, profile) -> object:
    """The bag read record by record, its index ignored."""
    return RosbagAdapter._salvage_bag1(path, SignalCollector(path, profile.sources["ros"]),
                                       "index not used")


@pytest.mark.parametrize("compression, chunk_bytes", [
    (Writer.CompressionFormat.LZ4, 4096), (Writer.CompressionFormat.BZ2, 20000),
    (UNCOMPRESSED, 1 << 20)])
def test_indexed_read_equals_the_record_walk(make_log, tmp_path, profile, compression,
                                             chunk_bytes):
    bag = tmp_path / "dive.bag"
    rewrite(make_log("paper-flow-sensor-covered", 31, "bag"), bag, compression, chunk_bytes)
    indexed = read_log(bag, profile.sources)
    assert not indexed.notes and indexed.damage is None
    assert_same_signals(indexed, walked(bag, profile))
    with AnyReader([bag]) as reader:
        wanted = [c for c in reader.connections if c.topic in profile.sources["ros"].topics]
        assert indexed.messages_read == sum(1 for _ in reader.messages(connections=wanted))


def test_a_chunk_with_a_damaged_index_is_walked(make_log, tmp_path, profile, monkeypatch):
    bag = tmp_path / "dive.bag"
    rewrite(make_log("paper-flow-sensor-covered", 31, "bag"), bag,
            Writer.CompressionFormat.LZ4, 4096)
    data = bytearray(bag.read_bytes())
    with bag.open("rb") as stream:
        index = read_bag_index(stream, len(data))
    view = memoryview(bytes(data))
    damaged_chunks = 0
    for chunk in index.chunks[::3]:
        _, _, after = record_at(view, chunk.position)         # the chunk record
        header_length = int.from_bytes(data[after:after + 4], "little")
        first_offset = after + 4 + header_length + 4 + 8      # entry 0: secs, nsecs, offset
        data[first_offset] ^= 0x01
        damaged_chunks += 1
    bag.write_bytes(bytes(data))
    assert damaged_chunks > 3
    walks = []
    monkeypatch.setattr(rosbag1_index, "_walk_chunk",
                        lambda *args: walks.append(1) or walk_chunk(*args))
    indexed = read_log(bag, profile.sources)
    assert len(walks) == damaged_chunks
    assert not indexed.notes and indexed.damage is None
    assert_same_signals(indexed, walked(bag, profile))


def test_inventory_counts_come_from_the_index(make_log, tmp_path):
    bag = tmp_path / "dive.bag"
    rewrite(make_log("paper-flow-sensor-covered", 31, "bag"), bag,
            Writer.CompressionFormat.LZ4, 4096)
    found, family = inventory(bag)
    assert family == "ros" and found.format == "bag"
    with AnyReader([bag]) as reader:
        expected: dict[str, int] = {}
        for connection in reader.connections:
            expected[connection.topic] = expected.get(connection.topic, 0) + connection.msgcount
        # rosbags states the end one nanosecond after the last message; the index, at it
        assert (found.start_ns, found.end_ns) == (reader.start_time, reader.end_time - 1)
    assert {t.name: t.count for t in found.topics} == expected
    assert all(t.fields for t in found.topics)
