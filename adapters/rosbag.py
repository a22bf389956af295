"""ROS 1 bags and ROS 2 bags (sqlite3 or MCAP storage; a directory, possibly split over
several storage files, or one storage file). Each storage is read directly: a ROS 1 bag
through its index (`adapters.rosbag1_index`, or record by record when it has none), db3
through SQL (`adapters.rosbag2_sqlite`), MCAP through its chunk indexes (`adapters.mcap`).
Message definitions come from the bag itself."""

import re
from pathlib import Path

from adapters.collect import SignalCollector
from adapters.inventory import LogInventory, TopicInfo, merged_inventory
from adapters.mcap import MCAP_MAGIC, McapAdapter, read_mcap
from adapters.rosbag1_index import read_bag_index, read_indexed_bag
from adapters.rosbag1_records import BagDamaged
from adapters.rosbag1_salvage import salvage_bag1
from adapters.rosbag2_compressed import (
    compressed_by_rosbag2,
    compressed_inventory,
    read_compressed,
)
from adapters.rosbag2_sqlite import Db3Bag
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

ROS1_MAGIC = b"#ROSBAG V2.0"
SQLITE_MAGIC = b"SQLite format 3\x00"


def _problem(error: BaseException) -> str:
    return str(error).strip() or type(error).__name__


def _head(path: Path, size: int) -> bytes:
    with path.open("rb") as stream:
        return stream.read(size)


def _recording_order(path: Path) -> list[str | int]:
    """rosbag2 numbers split files ``NAME_0``, ``NAME_1``, … ``NAME_10``: numbers as numbers."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def _storage_kind(path: Path) -> str | None:
    """``.mcap`` or ``.db3`` for a storage file, also one rosbag2 compressed whole
    (compression mode ``file``: ``NAME_0.db3.zstd``)."""
    suffixes = path.suffixes[-2:]
    if suffixes[-1:] == [".zstd"]:
        suffixes = suffixes[:-1]
    kind = suffixes[-1] if suffixes else None
    return kind if kind in (".mcap", ".db3") else None


def _storage_files(directory: Path) -> list[Path]:
    return sorted((p for p in directory.iterdir() if _storage_kind(p)), key=_recording_order)


def bag_storages(path: Path) -> list[Path]:
    """A ROS 2 bag's storage files in recording order (a file given alone: itself)."""
    return _storage_files(path) if path.is_dir() else [path]


def bag_topics(path: Path) -> set[str] | None:
    """The topics of a ROS 1 bag from its index alone; None where it has none to read."""
    try:
        with path.open("rb") as stream:
            index = read_bag_index(stream, path.stat().st_size, types=False)
    except BagDamaged:
        return None
    return {connection.topic for connection in index.connections.values()}


def _metadata(path: Path) -> Path:
    return (path if path.is_dir() else path.parent) / "metadata.yaml"


class RosbagAdapter:
    """Reads the profile's ROS topics, decoding only those connections."""

    family = "ros"
    formats = ("bag", "db3", "ros2-mcap")

    def sniff(self, path: Path) -> str | None:
        if path.is_dir():
            storage = _storage_files(path)
            if (path / "metadata.yaml").is_file() and storage:
                return "ros2-mcap" if _storage_kind(storage[0]) == ".mcap" else "db3"
            return None
        if not path.is_file():
            return None
        head = _head(path, 16)
        if head.startswith(ROS1_MAGIC):
            return "bag"
        if head.startswith(SQLITE_MAGIC):
            return "db3"
        if head.startswith(MCAP_MAGIC) and (path.parent / "metadata.yaml").is_file():
            return "ros2-mcap"
        return None

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        if fmt == "bag":
            try:
                return read_indexed_bag(path, SignalCollector(path, sources))
            except BagDamaged as error:
                return self._salvage_bag1(path, SignalCollector(path, sources), str(error))
        if compressed_by_rosbag2(_metadata(path)):
            return read_compressed(path, SignalCollector(path, sources), fmt)
        if fmt == "ros2-mcap":
            return read_mcap(bag_storages(path), path, sources, fmt)
        return Db3Bag(path, bag_storages(path)).read(SignalCollector(path, sources))

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        if fmt == "bag":
            try:
                with path.open("rb") as stream:
                    return read_bag_index(stream, path.stat().st_size).inventory()
            except BagDamaged as error:  # read what the records still say
                return self._salvaged_inventory(path, _problem(error))
        if compressed_by_rosbag2(_metadata(path)):
            return compressed_inventory(path, fmt)
        if fmt == "ros2-mcap":
            return merged_inventory(fmt, [McapAdapter().inventory(storage, "mcap")
                                          for storage in bag_storages(path)])
        return Db3Bag(path, bag_storages(path)).inventory()

    @staticmethod
    def _salvage_bag1(path: Path, collector: SignalCollector, reason: str) -> Signals:
        salvaged = salvage_bag1(path, collector)
        topics, stopped = salvaged.topics, salvaged.stopped
        if collector.count == 0:
            raise LogError(path, f"cannot open bag log ({reason}) and no message is "
                                 f"readable without its index ({stopped})")
        collector.require_topics(topics, " in the readable part")
        collector.notes.append(
            f"bag index unusable ({reason}); read {collector.count} messages record by record"
            + (f" up to the damage ({stopped})" if stopped else ""))
        if stopped:
            collector.damaged(f"bag damaged: {stopped}")
        return collector.finish("bag", None, None, topics)

    @staticmethod
    def _salvaged_inventory(path: Path, reason: str) -> LogInventory:
        salvaged = salvage_bag1(path, SignalCollector(path, LogSources({})))
        if not salvaged.counts:
            raise LogError(path, f"cannot open bag log ({reason}) and no message is readable "
                                 f"without its index ({salvaged.stopped})")
        topics = [TopicInfo(topic, salvaged.topics[topic], count)
                  for topic, count in sorted(salvaged.counts.items())]
        notes = [f"bag index unusable ({reason}); messages counted record by record"
                 + (f" up to the damage ({salvaged.stopped})" if salvaged.stopped else "")]
        return LogInventory("bag", None, None, topics, notes)
