"""The same simulated dive written in every format gives the same diagnosis and g."""

import numpy as np
import pytest

from adapters import detect_format, read_log
from auvdiag_cli.engine.diagnosis import diagnose
from auvdiag_errors import LogError
from models.store import load_model

ALL_FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "json-mcap", "protobuf-mcap", "tlog", "bin",
               "ulog", "alog"]
# A JSON- or Protocol Buffers-encoded MCAP is an MCAP like any other to the reader.
READ_AS = {"json-mcap": "mcap", "protobuf-mcap": "mcap"}
# MAVLink and DataFlash carry thruster commands as integer PWM µs (1/400 of full command)
# and sensor values as float32 (ULog: float32 throughout); ROS formats carry float64.
# A MOOS alog's times are whole milliseconds, as pLogger writes them: a command posted
# within a millisecond of a model step can land on the step either side of it.
G_TOLERANCE = {"tlog": 0.5, "bin": 0.5, "ulog": 0.5, "alog": 1.0}


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
    assert detect_format(log) == READ_AS.get(fmt, fmt)
    result = diagnose(log, profile, model)
    expected = reference[scenario]
    assert result.format == READ_AS.get(fmt, fmt)
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


# The format `auvdiag simulate` writes for each family a profile maps.
FAMILY_FORMATS = {"dataflash": "bin", "mavlink": "tlog", "ulog": "ulog", "csv": "csv",
                  "ros": "bag", "moos": "alog"}


def _simulated_families() -> list[tuple[str, str]]:
    from pathlib import Path

    from auvdiag_cli import api

    profiles = Path(api.__file__).parent / "vehicle" / "profiles"
    pairs = []
    for path in sorted(profiles.glob("*.toml")):
        profile = api.load_profile(path.stem)
        if profile.simulation is not None:
            pairs += [(path.stem, FAMILY_FORMATS[family]) for family in profile.sources
                      if family in FAMILY_FORMATS]
    return pairs


@pytest.mark.parametrize("profile_name, fmt", _simulated_families())
def test_every_shipped_profile_reads_the_logs_it_simulates(tmp_path, profile_name, fmt):
    """A simulated dive, in each format the profile maps, reads back with the profile: its
    operating flag (an ArduPilot ARM record) and records matched by a number (IMU I = 0)
    are written as the vehicle logs them."""
    from auvdiag_cli import api
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import get_scenario
    from auvdiag_cli.simulator.writers import write_log

    profile = api.load_profile(profile_name)
    dive = simulate(get_scenario("paper-normal", profile), profile, 1)
    path = tmp_path / f"dive.{fmt}"
    write_log(dive, profile, path, fmt)
    frame = ingest(path, profile).frame
    assert frame.operating.mean() > 0.9
    assert np.isfinite(frame.commands).all() and np.isfinite(frame.sensors).mean() > 0.9
    # Written again over it: refused, and the log stays whole.
    with pytest.raises(FileExistsError):
        write_log(dive, profile, path, fmt)
    assert ingest(path, profile).frame.commands.shape == frame.commands.shape


def test_a_simulated_log_that_fails_half_written_leaves_nothing_behind(tmp_path, monkeypatch):
    """A log cut short by a writer's failure would read as damaged, and block the next try
    ("exists already")."""
    from auvdiag_cli import api
    from auvdiag_cli.simulator import writers
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import get_scenario

    def half(dive, profile, path):
        path.write_bytes(b"\xa3\x95\x80")
        raise TypeError("a field the writer cannot pack")

    monkeypatch.setattr(writers, "write_dataflash", half)
    profile = api.load_profile("arducopter_quad")
    dive = simulate(get_scenario("paper-normal", profile), profile, 1)
    with pytest.raises(TypeError):
        writers.write_log(dive, profile, tmp_path / "dive.bin", "bin")
    assert list(tmp_path.iterdir()) == []
