"""ROS logs the way the profile's `[sources.ros]` table says the vehicle records them: ROS 1
bag, ROS 2 bag (sqlite3, mcap) through rosbags, and standalone MCAP (ros2 CDR, or JSON)
through the mcap library. Each topic's message type follows from the field paths read on it."""

import dataclasses
import heapq
import itertools
import json
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from adapters.fieldpath import parse_field_path
from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import (
    Record,
    dive_records,
    family_sources,
    operating_records,
)
from auvdiag_cli.vehicle.profile import Profile

# mavros's messages (mavros_msgs, not in rosbags' type stores): what an ArduPilot vehicle's
# bag holds, as its .msg files define them (constants left out).
MAVROS_DEFINITIONS = {
    "mavros_msgs/msg/RCOut": "std_msgs/Header header\nuint16[] channels\n",
    "mavros_msgs/msg/VFR_HUD": "std_msgs/Header header\nfloat32 airspeed\nfloat32 groundspeed\n"
                               "int16 heading\nfloat32 throttle\nfloat32 altitude\n"
                               "float32 climb\n",
    "mavros_msgs/msg/State": "std_msgs/Header header\nbool connected\nbool armed\nbool guided\n"
                             "bool manual_input\nstring mode\nuint8 system_status\n",
    "mavros_msgs/msg/StatusText": "std_msgs/Header header\nuint8 severity\nstring text\n",
    "mavros_msgs/msg/DebugValue": "std_msgs/Header header\nint32 index\nstring name\n"
                                  "float32 value_float\nint32 value_int\nfloat32[] data\n"
                                  "uint8 type\n",
}
STATUSTEXT_TYPE = "mavros_msgs/msg/StatusText"
MAV_SEVERITY_INFO = 6          # a segment marker's status text: news, not trouble
# The message type a topic carries, from the first step of the field paths read on it.
TYPES_BY_FIELD = {
    "twist": "geometry_msgs/msg/TwistStamped",
    "angular_velocity": "sensor_msgs/msg/Imu",
    "linear_acceleration": "sensor_msgs/msg/Imu",
    "vector": "geometry_msgs/msg/Vector3Stamped",
    "point": "geometry_msgs/msg/PointStamped",
    "channels": "mavros_msgs/msg/RCOut",
    "climb": "mavros_msgs/msg/VFR_HUD",
    "armed": "mavros_msgs/msg/State",
    "mode": "mavros_msgs/msg/State",
    "value_float": "mavros_msgs/msg/DebugValue",
}
SEGMENT_TYPES = {"data": "std_msgs/msg/String", "text": STATUSTEXT_TYPE}
NUMPY_TYPES = {"float64": np.float64, "float32": np.float32, "int8": np.int8, "int16": np.int16,
               "int32": np.int32, "int64": np.int64, "uint8": np.uint8, "uint16": np.uint16,
               "uint32": np.uint32, "uint64": np.uint64, "byte": np.uint8, "char": np.uint8,
               "bool": np.bool_}


def ros_topics(profile: Profile) -> dict[str, str]:
    """Topic -> message type of every topic the dive is written on."""
    sources = family_sources(profile, "ros")
    topics: dict[str, str] = {}
    for source in sources.signals.values():
        steps = parse_field_path(source.field)
        if steps[0] == "data":
            msgtype = ("std_msgs/msg/Float64MultiArray" if len(steps) > 1
                       else "std_msgs/msg/Float64")
        elif steps[0] in TYPES_BY_FIELD:
            msgtype = TYPES_BY_FIELD[str(steps[0])]
        else:
            raise ValueError(f"cannot write {source.topic}: no known message type has the "
                             f"field {source.field!r}")
        if topics.setdefault(source.topic, msgtype) != msgtype:
            raise ValueError(f"cannot write {source.topic}: its fields need two message types")
    if sources.segment is not None:
        field = str(parse_field_path(sources.segment.field)[0])
        if field not in SEGMENT_TYPES:
            raise ValueError(f"cannot write segment markers on {sources.segment.topic}: no "
                             f"known message type has the text field {field!r}")
        topics[sources.segment.topic] = SEGMENT_TYPES[field]
    return topics


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

    def __init__(self, ros1: bool, topics: dict[str, str]) -> None:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        self.ros1 = ros1
        self.topics = topics
        self.store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
        for msgtype, definition in MAVROS_DEFINITIONS.items():
            self.store.register(get_types_from_msg(definition, msgtype))
        self.types = self.store.types
        self.sequence = 0

    def zero(self, msgtype: str) -> Any:
        """A message of ``msgtype`` with every field zero or empty."""
        from rosbags.typesys.base import Nodetype

        def value(node: int, desc: Any) -> Any:
            if node == Nodetype.BASE:
                kind = desc[0]
                return "" if kind == "string" else np.zeros(1, NUMPY_TYPES[kind])[0].item()
            if node == Nodetype.NAME:
                return self.zero(desc)
            sub_node, sub_desc = desc[0]
            length = desc[1] if node == Nodetype.ARRAY else 0
            if sub_node == Nodetype.BASE and sub_desc[0] in NUMPY_TYPES:
                return np.zeros(length, NUMPY_TYPES[sub_desc[0]])
            return [value(sub_node, sub_desc) for _ in range(length)]

        _, fields = self.store.fielddefs[msgtype]
        return self.types[msgtype](**{name: value(node, desc) for name, (node, desc) in fields})

    def build(self, record: Record) -> Any:
        message = self.zero(self.topics[record.topic])
        if hasattr(message, "header"):
            self._stamp(message.header, record.time_ns, record.topic.strip("/").split("/")[0])
        if record.text is not None:
            _assign(message, record.text[0], record.text[1])
            if hasattr(message, "severity"):
                message.severity = MAV_SEVERITY_INFO
        for path, raw in record.fields:
            _assign(message, path, raw)
        for path, text in record.where:
            _assign(message, path, text)
        return message

    def _stamp(self, header: Any, time_ns: int, frame: str) -> None:
        header.stamp = self.types["builtin_interfaces/msg/Time"](sec=time_ns // 10**9,
                                                                 nanosec=time_ns % 10**9)
        header.frame_id = frame
        if self.ros1:
            self.sequence += 1
            header.seq = self.sequence

    def serialised(self, dive: SimulatedDive, profile: Profile,
                   extra: Sequence[ExtraTopic] = (),
                   encode: Callable[[Any, str], bytes] | None = None
                   ) -> Iterator[tuple[int, str, bytes]]:
        """(receive time ns, topic, serialised bytes) in time order; ``encode`` (a message,
        its type -> bytes): by default ROS 1's serialisation or CDR."""
        serialize = encode or (self.store.serialize_ros1 if self.ros1
                               else self.store.serialize_cdr)

        def dive_messages() -> Iterator[tuple[int, str, bytes]]:
            records = heapq.merge(dive_records(dive, profile, "ros"),
                                  operating_records(dive, profile, "ros"),
                                  key=lambda record: record.time_ns)
            for record in records:
                yield (record.time_ns, record.topic,
                       bytes(serialize(self.build(record), self.topics[record.topic])))

        def extra_messages(topic: ExtraTopic) -> Iterator[tuple[int, str, bytes]]:
            for index, time_ns in enumerate(topic.times_ns):
                message = topic.build(self.types, index)
                yield time_ns, topic.topic, bytes(serialize(message, topic.msgtype))

        yield from heapq.merge(dive_messages(), *map(extra_messages, extra),
                               key=lambda item: item[0])


def _assign(message: Any, path: str, value: float | str) -> None:
    """Set the field at ``path``, growing a sequence that is too short for its index; a
    number stored in an integer or a flag as the log would (rounded, true where not 0)."""
    steps = parse_field_path(path)
    parent = message
    for step, following in itertools.pairwise(steps):
        child = parent[step] if isinstance(step, int) else getattr(parent, step)
        if isinstance(following, int) and isinstance(child, np.ndarray) \
                and len(child) <= following:
            grown = np.zeros(following + 1, child.dtype)
            grown[:len(child)] = child
            setattr(parent, str(step), grown)
            child = grown
        parent = child
    last = steps[-1]
    if isinstance(last, int):
        if isinstance(parent, np.ndarray) and parent.dtype.kind in "iu":
            value = round(float(value))
        parent[last] = value
    elif isinstance(getattr(parent, last), bool):
        setattr(parent, last, bool(value))
    else:
        setattr(parent, last, value)


def all_topics(profile: Profile, extra: Sequence[ExtraTopic]) -> list[tuple[str, str]]:
    return [*ros_topics(profile).items(), *((e.topic, e.msgtype) for e in extra)]


def write_rosbag(dive: SimulatedDive, profile: Profile, path: Path, fmt: str,
                 extra: Sequence[ExtraTopic] = ()) -> None:
    """ROS 1 bag (``bag``, lz4 chunks) or ROS 2 bag (``db3``; ``ros2-mcap`` with zstd chunks)."""
    messages = RosMessages(fmt == "bag", ros_topics(profile))
    writer = _open_rosbag_writer(path, fmt)
    with writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=messages.store)
                       for topic, msgtype in all_topics(profile, extra)}
        for time_ns, topic, data in messages.serialised(dive, profile, extra):
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


def write_mcap(dive: SimulatedDive, profile: Profile, path: Path,
               extra: Sequence[ExtraTopic] = (), encoding: str = "cdr") -> None:
    """Standalone MCAP: profile ros2, ros2msg schemas and CDR messages in zstd chunks; or
    each message as a JSON object with a JSON Schema per channel (``encoding`` "json"), or
    as Protocol Buffers with a FileDescriptorSet per channel ("protobuf"), in lz4 chunks, as
    Foxglove's tools and many vehicles without ROS write them."""
    from mcap.writer import CompressionType, Writer

    from auvdiag_cli.simulator.writers.protobuf import ProtobufTypes, proto_name

    messages = RosMessages(False, ros_topics(profile))
    protobuf = ProtobufTypes(messages.store)
    schemas: dict[str, Callable[[str], tuple[str, str, bytes]]] = {
        "cdr": lambda t: (t, "ros2msg", messages.store.generate_msgdef(
            t, ros_version=2)[0].encode()),
        "json": lambda t: (t, "jsonschema", json.dumps(json_schema(messages.store, t)).encode()),
        "protobuf": lambda t: (proto_name(t), "protobuf", protobuf.descriptor_set(t))}
    encoders: dict[str, Callable[[Any, str], bytes] | None] = {
        "cdr": None, "json": lambda message, _: json.dumps(plain(message)).encode(),
        "protobuf": protobuf.encode}
    with path.open("wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD if encoding == "cdr"
                        else CompressionType.LZ4)
        writer.start(profile="ros2" if encoding == "cdr" else "", library="auvdiag simulate")
        channels = {topic: writer.register_channel(
            topic, encoding, writer.register_schema(*schemas[encoding](msgtype)))
            for topic, msgtype in all_topics(profile, extra)}
        ordered = messages.serialised(dive, profile, extra, encode=encoders[encoding])
        for sequence, (time_ns, topic, data) in enumerate(ordered):
            writer.add_message(channels[topic], log_time=time_ns, data=data,
                               publish_time=time_ns, sequence=sequence)
        writer.finish()


def plain(value: Any) -> Any:
    """A ROS message as JSON holds it: objects, lists, numbers and strings."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, list | tuple):
        return [plain(item) for item in value]
    return value


def json_schema(store: Any, msgtype: str) -> dict[str, Any]:
    """The JSON Schema of a ROS message type as `plain` writes it."""
    from rosbags.typesys.base import Nodetype

    def of(node: int, desc: Any) -> dict[str, Any]:
        if node == Nodetype.BASE:
            return {"type": {"string": "string", "bool": "boolean"}.get(desc[0], "number")}
        if node == Nodetype.NAME:
            return json_schema(store, desc)
        return {"type": "array", "items": of(*desc[0])}

    _, fields = store.fielddefs[msgtype]
    return {"type": "object", "properties": {name: of(node, desc)
                                             for name, (node, desc) in fields}}


# A node's log levels, ROS 1's (rosgraph_msgs/Log) as ROS 2 numbers them (rcl_interfaces).
ROS2_LEVELS = {1: 10, 2: 20, 4: 30, 8: 40, 16: 50}


def _header(types: Any, ros1: bool, index: int) -> Any:
    stamp = types["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
    return (types["std_msgs/msg/Header"](seq=index, stamp=stamp, frame_id="") if ros1
            else types["std_msgs/msg/Header"](stamp=stamp, frame_id=""))


def node_log(topic: str, ros1: bool, said: Sequence[tuple[int, int, str, str]]) -> ExtraTopic:
    """Nodes' log messages on ``topic`` (`/rosout`): (receive time ns, ROS 1 level, node,
    text) each, as ROS 1 (rosgraph_msgs/Log) or ROS 2 (rcl_interfaces/msg/Log) logs them."""
    def build(types: Any, index: int) -> Any:
        _, level, node, text = said[index]
        if ros1:
            return types["rosgraph_msgs/msg/Log"](
                header=_header(types, ros1, index), level=level, name=node, msg=text, file="",
                function="", line=0, topics=[])
        return types["rcl_interfaces/msg/Log"](
            stamp=types["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
            level=ROS2_LEVELS[level], name=node, msg=text, file="", function="", line=0)

    return ExtraTopic(topic, "rosgraph_msgs/msg/Log" if ros1 else "rcl_interfaces/msg/Log",
                      [at for at, *_ in said], build)


def status_texts(topic: str, ros1: bool, said: Sequence[tuple[int, int, str]]) -> ExtraTopic:
    """An autopilot's texts as mavros republishes them (``topic``: its statustext/recv):
    (receive time ns, MAVLink severity, text) each."""
    def build(types: Any, index: int) -> Any:
        _, severity, text = said[index]
        return types[STATUSTEXT_TYPE](header=_header(types, ros1, index), severity=severity,
                                      text=text)

    return ExtraTopic(topic, STATUSTEXT_TYPE, [at for at, *_ in said], build)


def hardware_status(topic: str, ros1: bool,
                    said: Sequence[tuple[int, Sequence[tuple[int, str, str]]]]) -> ExtraTopic:
    """The hardware's status as diagnostic_updater publishes it on ``topic``
    (`/diagnostics`): (receive time ns, [(level, name, message) of each status]) each."""
    def build(types: Any, index: int) -> Any:
        _, statuses = said[index]
        status = types["diagnostic_msgs/msg/DiagnosticStatus"]
        return types["diagnostic_msgs/msg/DiagnosticArray"](
            header=_header(types, ros1, index),
            status=[status(level=level, name=name, message=message, hardware_id="", values=[])
                    for level, name, message in statuses])

    return ExtraTopic(topic, "diagnostic_msgs/msg/DiagnosticArray", [at for at, _ in said],
                      build)
