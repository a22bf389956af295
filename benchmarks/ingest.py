"""Ingest throughput and memory: the adapters against the raw libraries, every format.

Simulates a one-hour dive (commands 10 Hz, flow 10 Hz, IMU 50 Hz, segment markers), writes
it in every format, with an unrelated camera topic (incompressible images, --image-gb in
total) in the ROS formats, then times in fresh processes:
  adapter  auvdiag's adapter reading the profile's signals (read_log);
  raw      the library alone iterating and decoding the same topics (for Protocol Buffers
           MCAP, the protobuf library's parser: a development dependency; for a MOOS alog,
           pandas' C parser splitting every line, the profile's variables kept);
and reports messages/s of each, their ratio, and each process's peak RSS.

Usage: python benchmarks/ingest.py [--workdir DIR] [--image-gb 1.0] [--keep]
"""

import argparse
import json
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path
from typing import Any

from bytecode import write_bytecode  # benchmarks/bytecode.py, beside this script

FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "protobuf-mcap", "tlog", "bin", "ulog", "alog"]
ROS_TOPICS = ["/thrusters/command", "/flow/velocity", "/imu/data", "/diagnosis/sequence"]
MAVLINK_TYPES = ["SERVO_OUTPUT_RAW", "NAMED_VALUE_FLOAT", "ATTITUDE", "STATUSTEXT"]
DATAFLASH_TYPES = ["RCOU", "FLOW", "IMU", "MSG"]
ULOG_TOPICS = ["actuator_motors", "airspeed", "vehicle_angular_velocity"]
ALOG_VARIABLES = ["DESIRED_THRUST_L", "DESIRED_THRUST_R", "FLOW_VELOCITY", "IMU_YAW_RATE",
                  "DMS_SEQUENCE"]
IMAGE_BYTES = 300_000


def make_logs(workdir: Path, image_gb: float) -> dict[str, Path]:
    import numpy as np

    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import DMS_ALL, PAPER_MISSION, Scenario
    from auvdiag_cli.simulator.writers import write_log
    from auvdiag_cli.simulator.writers.ros import ExtraTopic
    from auvdiag_cli.vehicle.profile import load_profile

    hour = Scenario("one-hour", "16 x (ZA, ZB, ZC, mission)", (DMS_ALL + PAPER_MISSION) * 16)
    profile = load_profile()
    dive = simulate(hour, profile, seed=1)
    frames = round(image_gb * 1e9 / IMAGE_BYTES)
    period_ns = round(dive.duration_s * 1e9 / frames)
    rng = np.random.default_rng(0)

    def image(types: object, index: int) -> object:
        t = types  # the store's classes
        stamp = t["builtin_interfaces/msg/Time"](sec=0, nanosec=0)  # type: ignore[index]
        header = (t["std_msgs/msg/Header"](seq=index, stamp=stamp, frame_id="cam")  # type: ignore[index]
                  if "seq" in t["std_msgs/msg/Header"].__dataclass_fields__  # type: ignore[index]
                  else t["std_msgs/msg/Header"](stamp=stamp, frame_id="cam"))  # type: ignore[index]
        # Fresh noise every frame: incompressible, so the files really hold the bytes.
        pixels = np.frombuffer(rng.bytes(IMAGE_BYTES), dtype=np.uint8)
        return t["sensor_msgs/msg/Image"](  # type: ignore[index]
            header=header, height=300, width=1000, encoding="mono8", is_bigendian=0,
            step=1000, data=pixels)

    camera = ExtraTopic("/camera/image_raw", "sensor_msgs/msg/Image",
                        [dive.start_ns + 5_000_000 + k * period_ns for k in range(frames)], image)
    paths = {}
    for fmt in FORMATS:
        path = workdir / {"bag": "dive.bag", "mcap": "dive.mcap", "tlog": "dive.tlog",
                          "bin": "dive.bin", "ulog": "dive.ulg", "alog": "dive.alog",
                          "protobuf-mcap": "dive_protobuf.mcap"}.get(fmt, f"dive_{fmt}")
        started = time.perf_counter()
        ros = fmt not in ("tlog", "bin", "ulog", "alog")
        write_log(dive, profile, path, fmt, [camera] if ros else [])
        size = sum(p.stat().st_size for p in path.rglob("*")) if path.is_dir() else \
            path.stat().st_size
        print(f"wrote {fmt:<9} {size / 1e9:6.2f} GB in {time.perf_counter() - started:5.1f} s",
              file=sys.stderr, flush=True)
        paths[fmt] = path
    return paths


def read_adapter(path: Path) -> int:
    from adapters import read_log
    from auvdiag_cli.vehicle.profile import load_profile

    signals = read_log(path, load_profile().sources)
    series = signals.series
    # thruster_0/1 share one message (an alog posts each alone); count messages, not samples.
    commands = len(series["thruster_0"]) + (len(series["thruster_1"])
                                            if signals.format == "alog" else 0)
    return commands + len(series["flow"]) + len(series["yaw_rate"]) + len(signals.markers)


def read_raw(path: Path, fmt: str) -> int:
    count = 0
    if fmt in ("bag", "db3", "ros2-mcap"):
        from rosbags.highlevel import AnyReader

        with AnyReader([path]) as reader:
            wanted = [c for c in reader.connections if c.topic in ROS_TOPICS]
            for connection, _, raw in reader.messages(connections=wanted):
                reader.deserialize(raw, connection.msgtype)
                count += 1
    elif fmt == "mcap":
        from mcap.reader import make_reader
        from mcap_ros2.decoder import DecoderFactory

        with path.open("rb") as stream:
            mcap_reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            for _ in mcap_reader.iter_decoded_messages(topics=ROS_TOPICS):
                count += 1
    elif fmt == "protobuf-mcap":
        count = _read_protobuf(path)
    elif fmt == "alog":
        import pandas as pd

        lines = pd.read_csv(path, sep=r"\s+", comment="%", header=None,
                            names=["time", "variable", "source", "value"], engine="c")
        count = int(lines["variable"].isin(ALOG_VARIABLES).sum())
    elif fmt == "ulog":
        from pyulog import ULog

        ulog = ULog(str(path), message_name_filter_list=ULOG_TOPICS)
        count = sum(len(d.data["timestamp"]) for d in ulog.data_list) + len(
            ulog.logged_messages)
    else:
        from pymavlink import DFReader, mavutil

        mav_reader = (mavutil.mavmmaplog(str(path)) if fmt == "tlog"
                      else DFReader.DFReader_binary(str(path), zero_time_base=True))
        types = MAVLINK_TYPES if fmt == "tlog" else DATAFLASH_TYPES
        while mav_reader.recv_match(type=types, blocking=False) is not None:
            count += 1
    return count


def _read_protobuf(path: Path) -> int:
    """The protobuf library's own parser (its C implementation where installed), each
    channel's message class built from its FileDescriptorSet."""
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
    from mcap.reader import make_reader

    classes: dict[int, Any] = {}
    count = 0
    with path.open("rb") as stream:
        for schema, _, message in make_reader(stream).iter_messages(topics=ROS_TOPICS):
            assert schema is not None            # every channel the simulator writes has one
            if schema.id not in classes:
                pool = descriptor_pool.DescriptorPool()
                for file in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
                    pool.Add(file)
                classes[schema.id] = message_factory.GetMessageClass(
                    pool.FindMessageTypeByName(schema.name))
            classes[schema.id].FromString(message.data)
            count += 1
    return count


def child(mode: str, fmt: str, path: Path) -> None:
    started = time.perf_counter()
    count = read_adapter(path) if mode == "adapter" else read_raw(path, fmt)
    seconds = time.perf_counter() - started
    from auvdiag_cli.peak_memory import peak_rss_mb  # imported after the timed read

    peak_mb = peak_rss_mb()
    print(json.dumps({"messages": count, "seconds": seconds, "peak_mb": peak_mb}))


def measure(mode: str, fmt: str, path: Path) -> dict[str, float]:
    out = subprocess.run([sys.executable, __file__, "--child", mode, fmt, str(path)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workdir", type=Path)
    parser.add_argument("--image-gb", type=float, default=1.0)
    parser.add_argument("--keep", action="store_true", help="keep the generated logs")
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child[0], args.child[1], Path(args.child[2]))
        return
    write_bytecode()          # as on an installed copy: no process compiles the sources
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="auvdiag-ingest-"))
    workdir.mkdir(parents=True, exist_ok=True)
    try:
        paths = make_logs(workdir, args.image_gb)
        rows = []
        for fmt, path in paths.items():
            adapter, raw = measure("adapter", fmt, path), measure("raw", fmt, path)
            rows.append((fmt, adapter, raw))
            print(f"measured {fmt}", file=sys.stderr, flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    print(f"Measured {date.today()} on {platform.machine()}, {platform.python_version()}, "
          f"one-hour dive, {args.image_gb:g} GB camera topic in the ROS formats.\n")
    print("| format | messages | adapter msg/s | raw library msg/s | adapter / raw | "
          "adapter peak RSS MB | raw peak RSS MB |")
    print("|---|---|---|---|---|---|---|")
    for fmt, adapter, raw in rows:
        a_rate = adapter["messages"] / adapter["seconds"]
        r_rate = raw["messages"] / raw["seconds"]
        print(f"| {fmt} | {int(adapter['messages'])} | {a_rate:,.0f} | {r_rate:,.0f} | "
              f"{a_rate / r_rate:.0%} | {adapter['peak_mb']:.0f} | {raw['peak_mb']:.0f} |")


if __name__ == "__main__":
    main()
