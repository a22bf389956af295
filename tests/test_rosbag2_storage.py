"""ROS 2 bags read straight from their storage (db3 through SQL, MCAP through its indexes),
against rosbags' own reader on the same bags: old and new db3 layouts, bags split over
several storage files, and bags whose messages rosbag2 compressed itself."""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import assert_same_signals
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

from adapters import inventory, read_log
from adapters.collect import SignalCollector
from adapters.rosbag2_compressed import read_compressed

STORAGE = {"db3": StoragePlugin.SQLITE3, "ros2-mcap": StoragePlugin.MCAP}


def rewrite(source: Path, target: Path, fmt: str, version: int = 9, parts: int = 1,
            compression: CompressionMode | None = None) -> None:
    """The messages of ``source`` as a bag at ``target``; with ``parts`` > 1 split over that
    many storage files in recording order, named as rosbag2 names them."""
    with AnyReader([source]) as reader:
        messages = list(reader.messages())
        connections = list(reader.connections)
        store = reader.typestore
    bounds = np.linspace(0, len(messages), parts + 1).astype(int)
    pieces = []
    for part in range(parts):
        piece = target.with_name(f"{target.name}-part{part}")
        writer = Writer(piece, version=version, storage_plugin=STORAGE[fmt])
        if compression is not None:
            writer.set_compression(compression, CompressionFormat.ZSTD)
        with writer:
            added = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store)
                     for c in connections}
            for connection, time_ns, raw in messages[bounds[part]:bounds[part + 1]]:
                writer.write(added[connection.id], time_ns, raw)
        pieces.append(piece)
    if parts == 1:
        pieces[0].rename(target)
        return
    target.mkdir()
    for part, piece in enumerate(pieces):
        storage = next(p for p in piece.iterdir() if p.suffix in (".db3", ".mcap"))
        storage.rename(target / f"{target.name}_{part}{storage.suffix}")
    (pieces[0] / "metadata.yaml").rename(target / "metadata.yaml")
    for piece in pieces:
        shutil.rmtree(piece)


@pytest.fixture(scope="module")
def dive(tmp_path_factory, dive_cache, profile) -> Path:
    from auvdiag_cli.simulator.writers import write_log

    path = tmp_path_factory.mktemp("ros2") / "dive"
    write_log(dive_cache("paper-flow-sensor-covered", 31), profile, path, "db3")
    return path


def drop_definitions(bag: Path) -> None:
    """What ROS 2 Humble and older record: no message definitions in the bag."""
    import sqlite3

    for storage in bag.glob("*.db3"):
        with sqlite3.connect(storage) as db:
            db.execute("DROP TABLE message_definitions")


@pytest.mark.parametrize("fmt, version, definitions", [
    ("db3", 9, True), ("db3", 8, True), ("db3", 8, False), ("ros2-mcap", 9, True)])
def test_storage_read_equals_rosbags(dive, tmp_path, profile, fmt, version, definitions):
    bag = tmp_path / "bag"
    rewrite(dive, bag, fmt, version)
    reference = read_compressed(bag, SignalCollector(bag, profile.sources["ros"]), fmt)
    if not definitions:
        drop_definitions(bag)
    read = read_log(bag, profile.sources)
    assert read.format == fmt and not read.notes
    assert_same_signals(read, reference)


@pytest.mark.parametrize("fmt", ["db3", "ros2-mcap"])
def test_a_bag_split_over_several_files_reads_as_one(dive, tmp_path, profile, fmt):
    whole, split = tmp_path / "whole", tmp_path / "split"
    rewrite(dive, whole, fmt)
    rewrite(dive, split, fmt, parts=11)                # _10 sorts after _9, not after _1
    assert len([p for p in split.iterdir() if p.name != "metadata.yaml"]) == 11
    read = read_log(split, profile.sources)
    assert read.format == fmt and not read.notes
    assert_same_signals(read, read_log(whole, profile.sources))
    assert (read.start_ns, read.end_ns) == (read_log(whole, profile.sources).start_ns,
                                            read_log(whole, profile.sources).end_ns)
    split_inventory, _ = inventory(split)
    whole_inventory, _ = inventory(whole)
    assert ({t.name: t.count for t in split_inventory.topics}
            == {t.name: t.count for t in whole_inventory.topics})
    assert split_inventory.start_ns == whole_inventory.start_ns


def test_messages_compressed_by_rosbag2_are_decompressed(dive, tmp_path, profile):
    plain, compressed = tmp_path / "plain", tmp_path / "compressed"
    rewrite(dive, plain, "ros2-mcap")
    rewrite(dive, compressed, "ros2-mcap", compression=CompressionMode.MESSAGE)
    assert_same_signals(read_log(compressed, profile.sources),
                        read_log(plain, profile.sources))


@pytest.mark.parametrize("fmt", ["db3", "ros2-mcap"])
def test_a_bag_compressed_file_by_file_is_read(fmt, dive, tmp_path, profile):
    """rosbag2's compression mode ``file`` leaves NAME_0.db3.zstd (or .mcap.zstd) beside
    metadata.yaml; it reads as the plain bag."""
    plain, compressed = tmp_path / "plain", tmp_path / "compressed"
    rewrite(dive, plain, fmt)
    rewrite(dive, compressed, fmt, compression=CompressionMode.FILE)
    assert [p.suffix for p in compressed.iterdir() if p.name != "metadata.yaml"] == [".zstd"]
    read = read_log(compressed, profile.sources)
    assert read.format == fmt
    assert_same_signals(read, read_log(plain, profile.sources))
    held, _ = inventory(compressed)
    assert {t.name for t in held.topics} == {t.name for t in inventory(plain)[0].topics}


def test_damaged_pages_in_a_db3_are_stepped_over(dive, tmp_path, profile):
    """A damaged page halfway through the messages table: sqlite stops there, the reader
    goes on at the next readable row and says which rows it could not read."""
    import sqlite3

    damaged = tmp_path / "damaged"
    shutil.copytree(dive, damaged)
    storage = next(damaged.glob("*.db3"))
    pages = storage.stat().st_size // 4096
    with sqlite3.connect(storage) as db:       # the page to damage: a leaf of the messages
        (page, rows_on_it), = db.execute(
            "SELECT pageno, ncell FROM dbstat WHERE name = 'messages' AND pagetype = 'leaf' "
            "AND pageno >= ? ORDER BY pageno LIMIT 1", (pages // 2,)).fetchall()
    db.close()
    with storage.open("r+b") as stream:
        stream.seek(4096 * (page - 1))
        stream.write(b"\xff" * 200)
    read, whole = read_log(damaged, profile.sources), read_log(dive, profile.sources)
    assert read.damage is not None and "unreadable (damaged pages); read on" in \
        read.damage.reason
    first, last = map(int, re.findall(r"rows (\d+) to (\d+)", read.damage.reason)[0])
    # Exactly the damaged page's rows are lost (all of them wanted), none after it.
    assert last - first + 1 == rows_on_it == whole.messages_read - read.messages_read
    assert read.end_ns == whole.end_ns


@pytest.mark.parametrize("path", ["sqlite", "pages"])
def test_a_damaged_message_is_left_out_and_the_read_goes_on(dive, tmp_path, profile,
                                                            monkeypatch, path):
    """One IMU message cut short: that message alone is left out, counted and noted as the
    damage; the IMU's messages after it and every other topic's are all read. Through
    sqlite (batches wait per topic) and from the pages (a batch per group of pages)."""
    import sqlite3

    import adapters.rosbag2_pages
    from adapters.sqlite_pages import NotPlain

    def refuse(*_: object) -> None:
        raise NotPlain("refused for the test")

    if path == "sqlite":
        monkeypatch.setattr(adapters.rosbag2_pages, "SqliteFile", refuse)
    damaged = tmp_path / "damaged"
    shutil.copytree(dive, damaged)
    storage = next(damaged.glob("*.db3"))
    with sqlite3.connect(storage) as db:
        db.execute("UPDATE messages SET data = substr(data, 1, 12) WHERE id = (SELECT m.id "
                   "FROM messages m JOIN topics t ON m.topic_id = t.id "
                   "WHERE t.name = '/imu/data' ORDER BY m.id LIMIT 1 OFFSET 100)")
    db.close()
    read, whole = read_log(damaged, profile.sources), read_log(dive, profile.sources)
    assert read.damage is not None and "1 message(s) of /imu/data left out" in read.damage.reason
    assert any("1 message(s) of /imu/data left out" in note for note in read.notes)
    imu_signals = {name for name, signal in profile.sources["ros"].signals.items()
                   if signal.topic == "/imu/data"}
    assert imu_signals and set(read.series) == set(whole.series)
    for name, series in whole.series.items():
        kept = read.series[name]
        if name in imu_signals:
            assert len(kept) == len(series) - 1
            assert np.array_equal(np.delete(series.times_ns, 100), kept.times_ns)
        else:
            assert len(kept) == len(series)
