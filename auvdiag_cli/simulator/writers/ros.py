"""ROS logs in the default Twin-Burger conventions (SPEC §4): ROS 1 bag, ROS 2 bag (sqlite3,
mcap) through rosbags, and standalone MCAP (ros2 CDR) through the mcap library."""

import heapq
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import COMMAND, FLOW, IMU, MARKER, dive_records

TOPICS = {
    COMMAND: ("/thrusters/command", "std_msgs/msg/Float64MultiArray"),
    FLOW: ("/flow/velocity", "geometry_msgs/msg/TwistStamped"),
    IMU: ("/imu/data", "sensor_msgs/msg/Imu"),
    MARKER: ("/diagnosis/sequence", "std_msgs/msg/String"),
}
COVARIANCE = np.zeros(9, dtype=np.float64)


@dataclass(frozen=True)
class ExtraTopic:
    """Unrelated traffic to record beside the dive (a camera, say): ``build(types, i)`` makes
    the i-th message from the type store's classes; it is received at ``times_ns[i]``."""

    topic: str
    msgtype: str
    times_ns: Sequence[int]
    build: Callable[[Any, int], Any]


class RosMessages:
    """Builds and serialises the dive's messages with a rosbags type store."""

    def __init__(self, ros1: bool) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.ros1 = ros1
        self.store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
        self.types = self.store.types
        self.sequence = 0

    def _header(self, time_ns: int, frame: str) -> Any:
        stamp = self.types["builtin_interfaces/msg/Time"](sec=time_ns // 10**9,
                                                          nanosec=time_ns % 10**9)
        if self.ros1:
            self.sequence += 1
            return self.types["std_msgs/msg/Header"](seq=self.sequence, stamp=stamp,
                                                     frame_id=frame)
        return self.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def build(self, kind: str, time_ns: int, values: tuple[float, ...], label: str) -> Any:
        t = self.types
        vector3 = t["geometry_msgs/msg/Vector3"]
        if kind == COMMAND:
            layout = t["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
            return t["std_msgs/msg/Float64MultiArray"](
                layout=layout, data=np.asarray(values, dtype=np.float64))
        if kind == FLOW:
            twist = t["geometry_msgs/msg/Twist"](linear=vector3(x=values[0], y=0.0, z=0.0),
                                                 angular=vector3(x=0.0, y=0.0, z=0.0))
            return t["geometry_msgs/msg/TwistStamped"](header=self._header(time_ns, "flow"),
                                                       twist=twist)
        if kind == IMU:
            return t["sensor_msgs/msg/Imu"](
                header=self._header(time_ns, "imu"),
                orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=COVARIANCE,
                angular_velocity=vector3(x=0.0, y=0.0, z=values[0]),
                angular_velocity_covariance=COVARIANCE,
                linear_acceleration=vector3(x=0.0, y=0.0, z=0.0),
                linear_acceleration_covariance=COVARIANCE)
        return t["std_msgs/msg/String"](data=label)

    def serialised(self, dive: SimulatedDive, extra: Sequence[ExtraTopic] = ()
                   ) -> Iterator[tuple[int, str, bytes]]:
        """(receive time ns, topic, serialised bytes) in time order."""
        serialize = self.store.serialize_ros1 if self.ros1 else self.store.serialize_cdr

        def dive_messages() -> Iterator[tuple[int, str, bytes]]:
            for record in dive_records(dive):
                topic, msgtype = TOPICS[record.kind]
                message = self.build(record.kind, record.time_ns, record.values, record.label)
                yield record.time_ns, topic, bytes(serialize(message, msgtype))

        def extra_messages(topic: ExtraTopic) -> Iterator[tuple[int, str, bytes]]:
            for index, time_ns in enumerate(topic.times_ns):
                message = topic.build(self.types, index)
                yield time_ns, topic.topic, bytes(serialize(message, topic.msgtype))

        yield from heapq.merge(dive_messages(), *map(extra_messages, extra),
                               key=lambda item: item[0])


def _all_topics(extra: Sequence[ExtraTopic]) -> list[tuple[str, str]]:
    return [*TOPICS.values(), *((e.topic, e.msgtype) for e in extra)]


def write_rosbag(dive: SimulatedDive, path: Path, fmt: str,
                 extra: Sequence[ExtraTopic] = ()) -> None:
    """ROS 1 bag (``bag``, lz4 chunks) or ROS 2 bag (``db3``; ``ros2-mcap`` with zstd chunks)."""
    messages = RosMessages(ros1=fmt == "bag")
    writer = _open_rosbag_writer(path, fmt)
    with writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=messages.store)
                       for topic, msgtype in _all_topics(extra)}
        for time_ns, topic, data in messages.serialised(dive, extra):
            writer.write(connections[topic], time_ns, data)


def _open_rosbag_writer(path: Path, fmt: str) -> Any:
    if fmt == "bag":
        from rosbags.rosbag1 import Writer as Ros1Writer

        writer1 = Ros1Writer(path)
        writer1.set_compression(Ros1Writer.CompressionFormat.LZ4)
        return writer1
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
    from rosbags.rosbag2 import Writer as Ros2Writer

    if fmt == "db3":
        return Ros2Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3)
    writer2 = Ros2Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    # Chunk-level zstd stays a standard MCAP that every MCAP tool reads.
    writer2.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    return writer2


def write_mcap(dive: SimulatedDive, path: Path, extra: Sequence[ExtraTopic] = ()) -> None:
    """Standalone MCAP, profile ros2: ros2msg schemas and CDR messages, zstd chunks."""
    from mcap.writer import CompressionType, Writer

    messages = RosMessages(ros1=False)
    with path.open("wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start(profile="ros2", library="auvdiag simulate")
        channels = {}
        for topic, msgtype in _all_topics(extra):
            text, _ = messages.store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(msgtype, "ros2msg", text.encode())
            channels[topic] = writer.register_channel(topic, "cdr", schema)
        for sequence, (time_ns, topic, data) in enumerate(messages.serialised(dive, extra)):
            writer.add_message(channels[topic], log_time=time_ns, data=data,
                               publish_time=time_ns, sequence=sequence)
        writer.finish()
