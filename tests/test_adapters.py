"""Logs written by the real writers read back exactly, in every ROS format."""

import numpy as np
import pytest

from adapters import detect_format, read_log
from adapters.fieldpath import field_getter, parse_field_path
from auvdiag_errors import LogError

FORMATS = ["bag", "db3", "ros2-mcap"]


@pytest.mark.parametrize("fmt", FORMATS)
def test_round_trip_values_and_markers(make_log, dive_cache, profile, fmt):
    dive = dive_cache("routine-and-mission", 11)
    log = make_log("routine-and-mission", 11, fmt)
    assert detect_format(log) == fmt
    signals = read_log(log, profile.sources)
    assert signals.format == fmt
    commands = np.asarray(dive.commands.values)
    np.testing.assert_allclose(signals.series["thruster_0"].values, commands[:, 0])
    np.testing.assert_allclose(signals.series["thruster_1"].values, commands[:, 1])
    np.testing.assert_allclose(signals.series["flow"].values,
                               np.asarray(dive.sensors["flow"].values)[:, 0])
    np.testing.assert_allclose(signals.series["yaw_rate"].values,
                               np.asarray(dive.sensors["yaw_rate"].values)[:, 0])
    gyro_times = np.asarray(dive.sensors["yaw_rate"].times_s)
    expected_ns = dive.start_ns + np.round(gyro_times * 1e9).astype(np.int64)
    np.testing.assert_array_equal(signals.series["yaw_rate"].times_ns, expected_ns)
    assert [m.label for m in signals.markers] == ["ZA", "ZB", "ZC", "MISSION"]
    first_ns = min([int(s.times_ns[0]) for s in signals.series.values()]
                   + [m.time_ns for m in signals.markers])
    assert signals.start_ns == first_ns


def test_ros2_bag_storage_file_is_read_like_its_directory(make_log, profile):
    directory = make_log("paper-normal", 11, "ros2-mcap")
    storage = next(directory.glob("*.mcap"))
    assert detect_format(storage) == "ros2-mcap"
    a = read_log(directory, profile.sources).series["flow"]
    b = read_log(storage, profile.sources).series["flow"]
    assert a.equals(b)


def test_field_paths():
    assert parse_field_path("twist.linear.x") == ("twist", "linear", "x")
    assert parse_field_path("data[1]") == ("data", 1)
    assert parse_field_path("a.b[2].c") == ("a", "b", 2, "c")
    assert field_getter("data[1]")({"data": [5.0, 7.0]}) == 7.0
    with pytest.raises(ValueError, match="cannot parse"):
        parse_field_path("data[x]")
    with pytest.raises(ValueError, match="empty step"):
        parse_field_path("twist..x")


@pytest.mark.parametrize(("path", "steps"), [
    ('rotors["motor-1"]', ("rotors", "motor-1")),
    ('["rpm 2"]', ("rpm 2",)),
    ('["pos.x"][0].value', ("pos.x", 0, "value")),
    ('a["say \\"hi\\""]', ("a", 'say "hi"')),
])
def test_a_key_that_is_no_plain_name_is_quoted_in_brackets(path, steps):
    """A JSON message's keys may hold dashes, spaces or dots: written as JSON strings in
    brackets, they are one step each, and `join_step` writes them back so."""
    from adapters.fieldpath import join_step

    assert parse_field_path(path) == steps
    message = {"rotors": {"motor-1": 0.5}, "rpm 2": 3, "pos.x": [{"value": 7}],
               "a": {'say "hi"': 1}}
    assert field_getter(path)(message) is not None
    written = ""
    for step in steps:
        written = f"{written}[{step}]" if isinstance(step, int) else join_step(written, step)
    assert parse_field_path(written) == steps


@pytest.mark.parametrize("path", ['a.["b"]', 'a["b"', 'a[b]', '["b"]x', "a.", ".a", ""])
def test_a_malformed_quoted_step_is_refused(path):
    with pytest.raises(ValueError, match="field path"):
        parse_field_path(path)


def test_unresolvable_field_names_the_file(make_log, profile):
    from dataclasses import replace

    from adapters import FieldSource

    sources = replace(profile.sources["ros"], signals={
        **profile.sources["ros"].signals,
        "flow": FieldSource("/flow/velocity", "twist.linear.w")})
    log = make_log("paper-normal", 11)
    with pytest.raises(LogError, match=r"has no field .twist.linear.w.") as error:
        read_log(log, {"ros": sources})
    assert str(log) in str(error.value)


def test_unindexed_ros1_bag_gives_the_same_signals(make_log, tmp_path, profile):
    log = make_log("paper-normal", 11, "bag")
    source = log.read_bytes()
    # A killed recorder leaves index_pos = 0 in the bag header record.
    position = source.index(b"index_pos=") + len(b"index_pos=")
    damaged = tmp_path / "unindexed.bag"
    damaged.write_bytes(source[:position] + b"\x00" * 8 + source[position + 8:])
    salvaged, intact = read_log(damaged, profile.sources), read_log(log, profile.sources)
    for name, series in intact.series.items():
        assert salvaged.series[name].equals(series), name
    assert [m.label for m in salvaged.markers] == ["MISSION"]
    assert "record by record" in salvaged.notes[0]


def test_file_that_only_looks_like_a_bag(tmp_path, profile):
    fake = tmp_path / "fake.bag"
    fake.write_bytes(b"#ROSBAG V2.0\n" + b"\xff" * 100)
    with pytest.raises(LogError, match="no message is readable") as error:
        read_log(fake, profile.sources)
    assert str(fake) in str(error.value)
