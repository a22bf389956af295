"""ROS 1 bags, read through their index (`adapters.rosbag1_index`), or record by record
when it is unusable (`adapters.rosbag1_salvage`). Message definitions come from the bag."""

from pathlib import Path

from adapters.collect import SignalCollector
from adapters.inventory import LogInventory, TopicInfo
from adapters.rosbag1_index import read_bag_index, read_indexed_bag
from adapters.rosbag1_records import BagDamaged
from adapters.rosbag1_salvage import salvage_bag1
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError


def _problem(error: BaseException) -> str:
    return str(error).strip() or type(error).__name__


def bag_topics(path: Path) -> set[str] | None:
    """The topics of a ROS 1 bag from its index alone; None where it has none to read."""
    try:
        with path.open("rb") as stream:
            index = read_bag_index(stream, path.stat().st_size, types=False)
    except BagDamaged:
        return None
    return {connection.topic for connection in index.connections.values()}


class RosbagAdapter:
    """Reads the profile's ROS topics, decoding only those connections."""

    family = "ros"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        try:
            return read_indexed_bag(path, SignalCollector(path, sources))
        except BagDamaged as error:
            return self._salvage_bag1(path, SignalCollector(path, sources), str(error))

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        try:
            with path.open("rb") as stream:
                return read_bag_index(stream, path.stat().st_size).inventory()
        except BagDamaged as error:  # read what the records still say
            return self._salvaged_inventory(path, _problem(error))

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
