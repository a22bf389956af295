"""Write a simulated dive as a real log in the default Twin-Burger conventions (SPEC §4),
plus its ground truth beside it."""

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.simulator.run import SimulatedDive, fault_summary

ROS_FORMATS = ("bag", "db3", "ros2-mcap")
COMMAND_TOPIC, FLOW_TOPIC, IMU_TOPIC = "/thrusters/command", "/flow/velocity", "/imu/data"
SEGMENT_TOPIC = "/diagnosis/sequence"
COVARIANCE = np.zeros(9, dtype=np.float64)


def truth_paths(log_path: Path) -> tuple[Path, Path]:
    """Where the ground truth of a log lives: ``NAME.truth.json`` and ``NAME.truth.csv``."""
    stem = log_path.parent / log_path.name.split(".")[0]
    return stem.with_name(stem.name + ".truth.json"), stem.with_name(stem.name + ".truth.csv")


def write_log(dive: SimulatedDive, path: Path, fmt: str) -> None:
    """Write ``dive`` to ``path`` in format ``fmt`` and its truth beside it."""
    if fmt not in ROS_FORMATS:
        raise ValueError(f"unknown log format {fmt!r} (writable: {', '.join(ROS_FORMATS)})")
    if path.exists():
        raise FileExistsError(f"{path}: exists already, not overwriting")
    _write_ros(dive, path, fmt)
    _write_truth(dive, path, fmt)


def _write_ros(dive: SimulatedDive, path: Path, fmt: str) -> None:
    from rosbags.typesys import Stores, get_typestore

    ros1 = fmt == "bag"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    types = store.types
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    sequence = iter(range(1 << 31))

    def header(time_s: float, frame: str) -> Any:
        t_ns = dive.start_ns + round(time_s * 1e9)
        stamp = types["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        if ros1:
            return types["std_msgs/msg/Header"](seq=next(sequence), stamp=stamp, frame_id=frame)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    vector3, quaternion = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    layout = types["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)

    def command(_: float, values: tuple[float, ...]) -> Any:
        return types["std_msgs/msg/Float64MultiArray"](
            layout=layout, data=np.asarray(values, dtype=np.float64))

    def flow(time_s: float, values: tuple[float, ...]) -> Any:
        twist = types["geometry_msgs/msg/Twist"](linear=vector3(x=values[0], y=0.0, z=0.0),
                                                 angular=vector3(x=0.0, y=0.0, z=0.0))
        return types["geometry_msgs/msg/TwistStamped"](header=header(time_s, "flow"), twist=twist)

    def imu(time_s: float, values: tuple[float, ...]) -> Any:
        return types["sensor_msgs/msg/Imu"](
            header=header(time_s, "imu"), orientation=quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=COVARIANCE,
            angular_velocity=vector3(x=0.0, y=0.0, z=values[0]),
            angular_velocity_covariance=COVARIANCE,
            linear_acceleration=vector3(x=0.0, y=0.0, z=0.0),
            linear_acceleration_covariance=COVARIANCE)

    builders: list[tuple[str, str, Any, Callable[[float, tuple[float, ...]], Any]]] = [
        (COMMAND_TOPIC, "std_msgs/msg/Float64MultiArray", dive.commands, command),
        (FLOW_TOPIC, "geometry_msgs/msg/TwistStamped", dive.flow, flow),
        (IMU_TOPIC, "sensor_msgs/msg/Imu", dive.imu, imu),
    ]
    records: list[tuple[int, str, bytes]] = []
    for topic, msgtype, stream, build in builders:
        for time_s, values in zip(stream.times_s, stream.values, strict=True):
            message = serialize(build(time_s, values), msgtype)
            records.append((dive.start_ns + round(time_s * 1e9), topic, bytes(message)))
    for time_s, label in dive.markers:
        message = serialize(types["std_msgs/msg/String"](data=label), "std_msgs/msg/String")
        records.append((dive.start_ns + round(time_s * 1e9), SEGMENT_TOPIC, bytes(message)))
    records.sort(key=lambda record: record[0])
    msgtypes = {topic: msgtype for topic, msgtype, _, _ in builders}
    msgtypes[SEGMENT_TOPIC] = "std_msgs/msg/String"

    writer = _open_writer(path, fmt)
    with writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=store)
                       for topic, msgtype in msgtypes.items()}
        for t_ns, topic, data in records:
            writer.write(connections[topic], t_ns, data)


def _open_writer(path: Path, fmt: str) -> Any:
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


def _write_truth(dive: SimulatedDive, path: Path, fmt: str) -> None:
    json_path, csv_path = truth_paths(path)
    fault = dive.scenario.fault
    # Report times count from the log's first message, which carries receive jitter.
    first_s = min(min(dive.commands.times_s), min(dive.flow.times_s), min(dive.imu.times_s),
                  *(t for t, _ in dive.markers))
    fault_info = fault_summary(fault)
    if fault_info is not None:
        fault_info["onset_s"] = round(float(fault_info["onset_s"]) - first_s, 6)  # type: ignore[arg-type]
    truth = {
        "log": path.name,
        "format": fmt,
        "scenario": dive.scenario.name,
        "description": dive.scenario.description,
        "seed": dive.seed,
        "duration_s": round(dive.duration_s, 3),
        "fault": fault_info,
        "expected": {
            "verdict": "normal" if fault is None else "fault",
            "component": None if fault is None else fault.component,
        },
        "phases": [{"name": name, "start_s": round(t, 3)} for name, t in dive.phase_starts_s],
        "truth_series": csv_path.name,
    }
    json_path.write_text(json.dumps(truth, indent=2) + "\n", encoding="utf-8")
    dive.truth.round(6).to_csv(csv_path, index=False)
