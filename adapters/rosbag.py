"""ROS 1 bags and ROS 2 bags (sqlite3 or mcap storage, directory or storage file) through
rosbags' AnyReader; message definitions come from the bag itself. A ROS 2 bag stored in one
MCAP file is read as MCAP (`adapters.mcap`)."""

from pathlib import Path
from typing import Any

from adapters.collect import SignalCollector
from adapters.fieldnames import ros_field_paths
from adapters.inventory import LogInventory, TopicInfo
from adapters.mcap import MCAP_MAGIC, McapAdapter, read_mcap, read_sequential
from adapters.ros_columns import TopicBatches
from adapters.rosbag1_index import read_bag_index, read_indexed_bag
from adapters.rosbag1_records import BagDamaged
from adapters.rosbag1_salvage import salvage_bag1
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

ROS1_MAGIC = b"#ROSBAG V2.0"
SQLITE_MAGIC = b"SQLite format 3\x00"


def _problem(error: BaseException) -> str:
    return str(error).strip() or type(error).__name__


def _head(path: Path, size: int) -> bytes:
    with path.open("rb") as stream:
        return stream.read(size)


def _storage_files(directory: Path) -> list[Path]:
    return sorted(p for p in directory.iterdir() if p.suffix in (".mcap", ".db3"))


def _open_reader(path: Path) -> Any:
    """An open AnyReader. Bags that carry no message definitions (ROS 2 Humble and older
    .db3) are decoded with the Humble type store."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
    reader.open()
    return reader


class RosbagAdapter:
    """Reads the profile's ROS topics, decoding only those connections."""

    family = "ros"
    formats = ("bag", "db3", "ros2-mcap")

    def sniff(self, path: Path) -> str | None:
        if path.is_dir():
            storage = _storage_files(path)
            if (path / "metadata.yaml").is_file() and storage:
                return "ros2-mcap" if storage[0].suffix == ".mcap" else "db3"
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
        if fmt == "ros2-mcap" and (path.is_file() or len(_storage_files(path)) == 1):
            # One MCAP storage file is plain MCAP: read through its chunk indexes, which is
            # several times faster than rosbags' message iteration.
            return read_mcap(self._mcap_file(path), path, sources, fmt)
        if fmt == "bag":
            try:
                return read_indexed_bag(path, SignalCollector(path, sources))
            except BagDamaged as error:
                return self._salvage_bag1(path, SignalCollector(path, sources), str(error))
        collector = SignalCollector(path, sources)
        try:
            reader = _open_reader(path)
        except Exception as error:  # rosbags raises several unrelated types on damage
            if fmt == "ros2-mcap":
                # The storage is plain MCAP: read what is readable, say what was lost.
                return read_sequential(self._mcap_file(path), collector, fmt)
            raise LogError(path, f"cannot open {fmt} log: {_problem(error)}") from None
        try:
            return self._extract(reader, collector, fmt)
        finally:
            reader.close()

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        if fmt == "bag":
            try:
                with path.open("rb") as stream:
                    return read_bag_index(stream, path.stat().st_size).inventory()
            except BagDamaged as error:  # read what the records still say
                return self._salvaged_inventory(path, _problem(error))
        try:
            reader = _open_reader(path)
        except Exception as error:  # damaged: read what the records still say
            if fmt == "ros2-mcap":
                inventory = McapAdapter().inventory(self._mcap_file(path), "mcap")
                inventory.format = fmt
                return inventory
            raise LogError(path, f"cannot open {fmt} log: {_problem(error)}") from None
        counts: dict[tuple[str, str], int] = {}
        for c in reader.connections:
            counts[c.topic, c.msgtype] = counts.get((c.topic, c.msgtype), 0) + c.msgcount
        span = (int(reader.start_time), int(reader.end_time))
        fields = {msgtype: tuple(ros_field_paths(reader.typestore, msgtype))
                  for _, msgtype in counts}
        reader.close()
        topics = [TopicInfo(topic, msgtype, count, fields[msgtype])
                  for (topic, msgtype), count in sorted(counts.items())]
        return LogInventory(fmt, *span, topics)

    @staticmethod
    def _salvage_bag1(path: Path, collector: SignalCollector, reason: str) -> Signals:
        salvaged = salvage_bag1(path, collector)
        topics, stopped = salvaged.topics, salvaged.stopped
        if collector.count == 0:
            raise LogError(path, f"cannot open bag log ({reason}) and no message is "
                                 f"readable without its index ({stopped})")
        missing = collector.missing_topics(set(topics))
        if missing:
            raise LogError(path, f"missing topic(s) {', '.join(missing)} in the readable part")
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

    @staticmethod
    def _mcap_file(path: Path) -> Path:
        return _storage_files(path)[0] if path.is_dir() else path

    def _extract(self, reader: Any, collector: SignalCollector, fmt: str) -> Signals:
        topics = {c.topic: c.msgtype for c in reader.connections}
        missing = collector.missing_topics(set(topics))
        if missing:
            raise LogError(collector.path, f"missing topic(s) {', '.join(missing)}")
        connections = [c for c in reader.connections if c.topic in collector.topics]
        batches = TopicBatches(collector, topics, reader.is2, reader.typestore,
                               reader.deserialize)

        def feed() -> None:
            for connection, timestamp, raw in reader.messages(connections=connections):
                batches.append(connection.topic, int(timestamp), raw)

        batches.fill(feed)
        return collector.finish(fmt, int(reader.start_time), int(reader.end_time), topics)
