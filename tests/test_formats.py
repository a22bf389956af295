"""The same simulated dive written in every format gives the same diagnosis and g."""

import numpy as np
import pytest

from adapters import detect_format, read_log
from auvdiag_cli.engine.diagnosis import diagnose
from auvdiag_errors import LogError
from models.store import load_model

ALL_FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "tlog", "bin", "ulog"]
# MAVLink and DataFlash carry thruster commands as integer PWM µs (1/400 of full command)
# and sensor values as float32 (ULog: float32 throughout); ROS formats carry float64.
G_TOLERANCE = {"tlog": 0.5, "bin": 0.5, "ulog": 0.5}


@pytest.fixture(scope="module")
def model():
    return load_model()


@pytest.fixture(scope="module")
def reference(make_log, profile, model):
    return {scenario: diagnose(make_log(scenario, 21, "ros2-mcap"), profile, model)
            for scenario in ("paper-flow-sensor-covered", "routine-and-mission")}


@pytest.mark.parametrize("fmt", ALL_FORMATS)
@pytest.mark.parametrize("scenario", ["paper-flow-sensor-covered", "routine-and-mission"])
def test_every_format_gives_the_same_diagnosis(make_log, profile, model, reference, fmt,
                                               scenario):
    log = make_log(scenario, 21, fmt)
    assert detect_format(log) == fmt
    result = diagnose(log, profile, model)
    expected = reference[scenario]
    assert result.format == fmt
    assert (result.verdict, result.component, result.case, result.b) == (
        expected.verdict, expected.component, expected.case, expected.b)
    assert [s.segment.name for s in result.segments] == [s.segment.name
                                                         for s in expected.segments]
    if expected.detected_at_s is not None:
        assert result.detected_at_s == pytest.approx(expected.detected_at_s, abs=0.25)
        assert result.onset_s == pytest.approx(expected.onset_s, abs=0.25)
    assert len(result.histories.time_s) == pytest.approx(len(expected.histories.time_s), abs=1)
    steps = min(len(result.histories.time_s), len(expected.histories.time_s))
    np.testing.assert_allclose(result.histories.matching.g_percent[:steps],
                               expected.histories.matching.g_percent[:steps],
                               atol=G_TOLERANCE.get(fmt, 1e-6), equal_nan=True)


def test_standalone_mcap_with_json_and_ros1_encodings(tmp_path, profile, dive_cache):
    """The mcap adapter decodes JSON- and ROS 1-encoded channels too."""
    import json

    from mcap.writer import Writer

    dive = dive_cache("paper-normal", 21)
    path = tmp_path / "json.mcap"
    with path.open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile="", library="test")
        schema = writer.register_schema("Reading", "jsonschema", b"{}")
        channels = {topic: writer.register_channel(topic, "json", schema) for topic in
                    ("/thrusters/command", "/flow/velocity", "/imu/data")}
        flow, gyro = dive.sensors["flow"], dive.sensors["yaw_rate"]
        for topic, stream_, encode in (
                ("/thrusters/command", dive.commands, lambda v: {"data": list(v)}),
                ("/flow/velocity", flow, lambda v: {"twist": {"linear": {"x": v[0]}}}),
                ("/imu/data", gyro, lambda v: {"angular_velocity": {"z": v[0]}})):
            for t, v in zip(stream_.times_s, stream_.values, strict=True):
                time_ns = dive.start_ns + round(t * 1e9)
                writer.add_message(channels[topic], log_time=time_ns, publish_time=time_ns,
                                   data=json.dumps(encode(v)).encode())
        writer.finish()
    signals = read_log(path, profile.sources)
    assert signals.format == "mcap"
    np.testing.assert_allclose(signals.series["flow"].values,
                               np.asarray(dive.sensors["flow"].values)[:, 0])


def test_ros1_encoded_mcap(tmp_path, profile):
    from mcap_ros1._vendor.genpy.dynamic import generate_dynamic
    from mcap_ros1.writer import Writer

    classes = {name: generate_dynamic(name, text)[name] for name, text in (
        ("std_msgs/Float64MultiArray", "float64[] data"),
        ("geometry_msgs/Vector3Stamped", "float64 x\nfloat64 y\nfloat64 z"))}
    path = tmp_path / "ros1.mcap"
    with path.open("wb") as stream:
        writer = Writer(stream)
        for k in range(50):
            t = 1_000_000_000 + k * 100_000_000
            writer.write_message("/thrusters/command",
                                 classes["std_msgs/Float64MultiArray"](data=[0.5, 0.25]),
                                 log_time=t)
            writer.write_message("/flow/velocity",
                                 classes["geometry_msgs/Vector3Stamped"](x=0.1, y=0.0, z=0.0),
                                 log_time=t + 1)
            writer.write_message("/imu/data",
                                 classes["geometry_msgs/Vector3Stamped"](x=0.0, y=0.0, z=0.2),
                                 log_time=t + 2)
        writer.finish()
    from dataclasses import replace

    from adapters import FieldSource

    ros = profile.sources["ros"]
    sources = replace(ros, signals={**ros.signals,
                                    "flow": FieldSource("/flow/velocity", "x"),
                                    "yaw_rate": FieldSource("/imu/data", "z")})
    signals = read_log(path, {"ros": sources})
    assert signals.series["thruster_1"].values[-1] == 0.25
    assert signals.series["yaw_rate"].values[0] == pytest.approx(0.2)
    assert len(signals.series["flow"]) == 50


def test_dataflash_log_without_the_flow_record_names_it(tmp_path, make_log, profile):
    source = make_log("paper-normal", 21, "bin").read_bytes()
    # Drop every FLOW record by rewriting the file record by record (FMT records give each
    # type's name and length).
    kept, position = bytearray(), 0
    lengths, names = {}, {}
    while position < len(source):
        type_id = source[position + 2]
        if type_id == 128:
            lengths[source[position + 3]] = source[position + 4]
            names[source[position + 3]] = source[position + 5:position + 9].rstrip(b"\0")
            length = 89
        else:
            length = lengths[type_id]
        if names.get(type_id) != b"FLOW":
            kept += source[position:position + length]
        position += length
    damaged = tmp_path / "noflow.bin"
    damaged.write_bytes(bytes(kept))
    with pytest.raises(LogError, match=r"no messages for signal\(s\) flow \(FLOW\)"):
        read_log(damaged, profile.sources)
