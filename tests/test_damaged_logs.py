"""Damaged, partial and odd logs: either the readable part is analysed and the report says
what was lost, or one line names the file and the problem (exit 2). Never a traceback."""

import shutil

import pytest
from helpers import diagnose_outcome
from typer.testing import CliRunner

from adapters.ulog import walk_framing
from auvdiag_cli.cli import app
from auvdiag_cli.engine.silences import EDGE_S

FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "tlog", "bin", "ulog"]
DAMAGE_WORDS = ("cut short", "damaged", "index unusable")
runner = CliRunner()


def storage_file(log, fmt):
    if fmt in ("db3", "ros2-mcap"):
        return next(p for p in log.iterdir() if p.suffix in (".db3", ".mcap"))
    return log


def copy_log(log, fmt, target):
    if log.is_dir():
        shutil.copytree(log, target)
    else:
        shutil.copy(log, target)
    return target, storage_file(target, fmt)


def outcome(log):
    """The exit status and the report (None for a log refused in one line)."""
    code, report = diagnose_outcome(log)
    return code, report if isinstance(report, dict) else None


@pytest.mark.parametrize("fraction", [0.05, 0.5, 0.97])
@pytest.mark.parametrize("fmt", FORMATS)
def test_truncated_logs(make_log, tmp_path, fmt, fraction):
    log, storage = copy_log(make_log("paper-flow-sensor-covered", 31, fmt), fmt,
                            tmp_path / f"cut.{fmt}")
    data = storage.read_bytes()
    cut = int(len(data) * fraction)
    storage.write_bytes(data[:cut])
    while fmt == "ulog" and walk_framing(storage).cut_at is None:
        # A ULog has no footer or index: one cut exactly between two messages reads as a
        # complete log (see docs/limits.md), so the cut is moved off the boundary.
        cut += 1
        storage.write_bytes(data[:cut])
    code, report = outcome(log)
    if fraction >= 0.5 and fmt != "db3":
        # Half a log or more is always analysed; sqlite refuses a cut .db3 file outright
        # (docs/robustness.md), and a cut in the first seconds may leave too little.
        assert code != 2, f"{fmt} cut at {fraction:.0%} was not salvaged"
    if code != 2:
        assert any(word in note for note in report["notes"] for word in DAMAGE_WORDS)
        assert report["duration_s"] < 175.0


@pytest.mark.parametrize("fmt", ["mcap", "tlog", "bin", "bag"])
def test_zero_length_files(tmp_path, fmt):
    empty = tmp_path / f"empty.{fmt}"
    empty.touch()
    assert outcome(empty) == (2, None)


def test_mostly_intact_mcap_is_still_diagnosed(make_log, tmp_path):
    log, storage = copy_log(make_log("paper-flow-sensor-covered", 31, "mcap"), "mcap",
                            tmp_path / "late_cut.mcap")
    data = storage.read_bytes()
    storage.write_bytes(data[: len(data) - 5000])
    code, report = outcome(log)
    assert code == 1 and report["component"] == "flow_sensor"
    assert any("damaged" in note for note in report["notes"])


def test_mcap_without_summary_is_read_sequentially(tmp_path, dive_cache, profile):
    from mcap.reader import make_reader
    from mcap.writer import IndexType, Writer

    from auvdiag_cli.simulator.writers.ros import RosMessages, ros_topics

    messages = RosMessages(False, ros_topics(profile))
    path = tmp_path / "nosummary.mcap"
    with path.open("wb") as stream:
        writer = Writer(stream, use_chunking=False, use_summary_offsets=False,
                        use_statistics=False, index_types=IndexType.NONE,
                        repeat_channels=False, repeat_schemas=False)
        writer.start(profile="ros2", library="test")
        channels = {}
        for topic, msgtype in messages.topics.items():
            text, _ = messages.store.generate_msgdef(msgtype, ros_version=2)
            channels[topic] = writer.register_channel(
                topic, "cdr", writer.register_schema(msgtype, "ros2msg", text.encode()))
        for time_ns, topic, data in messages.serialised(dive_cache("paper-normal", 31), profile):
            writer.add_message(channels[topic], log_time=time_ns, data=data,
                               publish_time=time_ns)
        writer.finish()
    with path.open("rb") as stream:
        assert make_reader(stream).get_summary() is None
    code, report = outcome(path)
    assert code == 0 and report["verdict"] == "normal"
    assert report["completeness"]["status"] == "complete"


def test_unindexed_ros1_bag_is_read_record_by_record(make_log, tmp_path):
    """What a killed recorder leaves: index_pos = 0 and no index records."""
    log = make_log("paper-flow-sensor-covered", 31, "bag")
    source = log.read_bytes()
    position = source.index(b"index_pos=") + len(b"index_pos=")
    damaged = tmp_path / "recording.bag.active"
    damaged.write_bytes(source[:position] + b"\x00" * 8 + source[position + 8:])
    code, report = outcome(damaged)
    _, intact = outcome(log)
    assert code == 1 and report["component"] == "flow_sensor"
    assert report["onset_s"] == intact["onset_s"]
    assert report["detected_at_s"] == intact["detected_at_s"]
    assert any("read 12251 messages record by record" in note for note in report["notes"])


def test_unknown_message_types_on_unrelated_topics_are_ignored(tmp_path, dive_cache, profile):
    """A bag with a custom message type (definition only in the bag) on another topic."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_types_from_msg

    from auvdiag_cli.simulator.writers.ros import RosMessages, ros_topics

    messages = RosMessages(False, ros_topics(profile))
    store = messages.store
    store.register(get_types_from_msg("uint8[] pixels\nstring encoding", "acme_msgs/msg/Frame"))
    path = tmp_path / "with_camera"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=store)
                       for topic, msgtype in messages.topics.items()}
        camera = writer.add_connection("/camera/frame", "acme_msgs/msg/Frame", typestore=store)
        frame = store.types["acme_msgs/msg/Frame"](
            pixels=__import__("numpy").zeros(1000, dtype="uint8"), encoding="mono8")
        frame_bytes = bytes(store.serialize_cdr(frame, "acme_msgs/msg/Frame"))
        for index, (time_ns, topic, data) in enumerate(
                messages.serialised(dive_cache("paper-normal", 31), profile)):
            writer.write(connections[topic], time_ns, data)
            if index % 50 == 0:
                writer.write(camera, time_ns, frame_bytes)
    code, report = outcome(path)
    assert code == 0 and report["verdict"] == "normal"


@pytest.mark.parametrize(("fmt", "missing"), [("tlog", "ATTITUDE"), ("bin", "IMU"),
                                              ("mcap", "/imu/data"), ("db3", "/imu/data")])
def test_log_missing_one_needed_source_is_one_line(make_log, tmp_path, fmt, missing):
    from importlib import resources

    original = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    renamed = {"ATTITUDE": "ATTITUDE_QUATERNION", "IMU": "IMU2", "/imu/data": "/imu/other"}
    profile_path = tmp_path / "p.toml"
    profile_path.write_text(original.replace(f'"{missing}"', f'"{renamed[missing]}"'))
    log = make_log("paper-normal", 31, fmt)
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(profile_path)])
    assert result.exit_code == 2
    line = result.stderr.strip()
    assert "\n" not in line and str(log) in line and renamed[missing] in line


@pytest.mark.parametrize("pause_s", [300.0, 9.8 * 3600])
def test_recording_pause_is_reported_and_raises_no_false_alarm(tmp_path, dive_cache, profile,
                                                               pause_s):
    """All topics silent for 5 minutes or 9.8 hours (a paused recorder or a clock jump
    forward): the silence costs nothing, only its edges stay on the grid."""
    import copy

    from auvdiag_cli.simulator.writers import write_log

    dive = copy.deepcopy(dive_cache("paper-normal", 31))
    for stream in (dive.commands, *dive.sensors.values()):
        stream.times_s = [t + pause_s if t > 60.0 else t for t in stream.times_s]
    path = tmp_path / "paused.mcap"
    write_log(dive, profile, path, "mcap")
    code, report = outcome(path)
    assert code == 0 and report["verdict"] == "normal"
    import re

    gaps = [re.search(r"gap in (\w+) from ([\d.]+) s to ([\d.]+) s", note)
            for note in report["notes"]]
    spans = {m.group(1): (float(m.group(2)), float(m.group(3))) for m in gaps if m}
    assert set(spans) == {"thruster_0", "thruster_1", "flow", "yaw_rate"}
    for start, end in spans.values():
        assert 59.8 <= start <= 60.1 and 59.9 + pause_s <= end <= 60.2 + pause_s
    left_off = [note for note in report["notes"] if "left off the model grid" in note]
    assert bool(left_off) == (pause_s > 2 * EDGE_S + 60)
    if left_off:
        assert float(left_off[0].split()[0]) == pytest.approx(pause_s - 2 * EDGE_S, abs=2)
