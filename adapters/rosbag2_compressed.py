"""ROS 2 bags whose messages rosbag2 compressed itself (compression mode ``message`` in
metadata.yaml): only rosbags undoes that, so these are read through its AnyReader. Such a
payload read as plain CDR decodes silently as garbage, which is why the storage readers
never see these bags."""

import re
from pathlib import Path
from typing import Any

from adapters.collect import SignalCollector
from adapters.fieldnames import ros_field_paths
from adapters.inventory import LogInventory, TopicInfo
from adapters.ros_columns import TopicBatches
from adapters.signals import Signals
from auvdiag_errors import LogError

_COMPRESSION_MODE = re.compile(r"^\s*compression_mode:\s*['\"]?(\w*)", re.MULTILINE)


def compressed_by_rosbag2(metadata: Path) -> bool:
    """Does this metadata.yaml say rosbag2 compressed the messages or files?"""
    try:
        found = _COMPRESSION_MODE.search(metadata.read_text(errors="replace"))
    except OSError:
        return False
    return found is not None and found.group(1).upper() in ("MESSAGE", "FILE")


def _problem(error: BaseException) -> str:
    return str(error).strip() or type(error).__name__


def _open_reader(path: Path, fmt: str) -> Any:
    """An open AnyReader. Bags that carry no message definitions (ROS 2 Humble and older
    .db3) are decoded with the Humble type store."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    try:
        reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except Exception as error:  # rosbags raises several unrelated types on damage
        raise LogError(path, f"cannot open {fmt} log: {_problem(error)}") from None
    return reader


def read_compressed(path: Path, collector: SignalCollector, fmt: str) -> Signals:
    reader = _open_reader(path, fmt)
    try:
        topics = {c.topic: c.msgtype for c in reader.connections}
        collector.require_topics(topics)
        connections = [c for c in reader.connections if c.topic in collector.topics]
        batches = TopicBatches(collector, topics, True, reader.typestore, reader.deserialize)

        def feed() -> None:
            for connection, timestamp, raw in reader.messages(connections=connections):
                batches.append(connection.topic, int(timestamp), raw)

        batches.fill(feed)
        return collector.finish(fmt, int(reader.start_time), int(reader.end_time), topics)
    finally:
        reader.close()


def compressed_inventory(path: Path, fmt: str) -> LogInventory:
    reader = _open_reader(path, fmt)
    try:
        counts: dict[tuple[str, str], int] = {}
        for c in reader.connections:
            counts[c.topic, c.msgtype] = counts.get((c.topic, c.msgtype), 0) + c.msgcount
        topics = [TopicInfo(topic, msgtype, count,
                            tuple(ros_field_paths(reader.typestore, msgtype)))
                  for (topic, msgtype), count in sorted(counts.items())]
        return LogInventory(fmt, int(reader.start_time), int(reader.end_time), topics)
    finally:
        reader.close()
