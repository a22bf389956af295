"""PX4 ULog: files packed to the ULog specification read back through pyulog with the right
values, times, instances and markers; the PX4 profile; damage handled like other formats."""

from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from adapters import detect_format, inventory, read_log
from adapters.ulog import walk_framing
from auvdiag_cli.cli import app
from auvdiag_cli.simulator.writers.ulog import BOOT_BEFORE_LOG_US, UlogTopic, write_ulog_file
from auvdiag_cli.vehicle.profile import load_profile, profile_text
from auvdiag_errors import LogError

runner = CliRunner()
RATE_HZ, SECONDS = 10, 30.0


def test_round_trip_values_times_and_markers(make_log, dive_cache, profile):
    dive = dive_cache("routine-and-mission", 11)
    log = make_log("routine-and-mission", 11, "ulog")
    assert detect_format(log) == "ulog"
    signals = read_log(log, profile.sources)
    commands = np.asarray(dive.commands.values)
    # ULog fields are float32.
    np.testing.assert_allclose(signals.series["thruster_0"].values, commands[:, 0],
                               atol=1e-6)
    np.testing.assert_allclose(signals.series["yaw_rate"].values,
                               np.asarray(dive.sensors["yaw_rate"].values)[:, 0], atol=1e-6)
    # PX4's clock counts µs from boot, which came a little before the log.
    boot_ns = dive.start_ns - BOOT_BEFORE_LOG_US * 1000
    expected_us = (dive.start_ns + np.round(np.asarray(dive.sensors["flow"].times_s) * 1e9)
                   .astype(np.int64) - boot_ns) // 1000
    np.testing.assert_array_equal(signals.series["flow"].times_ns, expected_us * 1000)
    assert [m.label for m in signals.markers] == ["ZA", "ZB", "ZC", "MISSION"]


def _px4_log(path, instances=(0,), armed_from_s=5.0):
    """A PX4 UUV's topics: four motors, the gyro (in ``instances``), the vertical speed and
    the armed flag, sampled at 10 Hz from 20 s after boot."""
    times = 20_000_000 + np.arange(int(SECONDS * RATE_HZ)) * (1_000_000 // RATE_HZ)
    t = (times - times[0]) / 1e6
    motors = np.column_stack([0.3 * np.sin(0.2 * t + k) for k in range(4)])
    topics = [UlogTopic("actuator_motors", ("control[0]", "control[1]", "control[2]",
                                            "control[3]"), times, motors)]
    for instance in instances:
        gyro = np.column_stack([0.01 * (instance + 1) * np.sin(t), 0.02 * np.cos(t),
                                0.1 * (instance + 1) * np.sin(0.5 * t)])
        topics.append(UlogTopic("vehicle_angular_velocity", ("xyz[0]", "xyz[1]", "xyz[2]"),
                                times, gyro, instance))
    topics.append(UlogTopic("vehicle_local_position", ("vz",), times,
                            (0.05 * np.sin(0.3 * t))[:, None]))
    topics.append(UlogTopic("actuator_armed", ("armed",), times,
                            (t >= armed_from_s).astype(float)[:, None]))
    write_ulog_file(path, topics, int(times[0]), texts=[(int(times[50]), "DMS M1")])
    return path


def test_px4_profile_reads_a_px4_log_and_inspect_lists_it(tmp_path):
    log = _px4_log(tmp_path / "dive.ulg")
    px4 = load_profile(Path("px4_uuv"))
    signals = read_log(log, px4.sources)
    assert set(signals.series) == {"motor_1", "motor_2", "motor_3", "motor_4", "roll_rate",
                                   "pitch_rate", "yaw_rate", "heave", "operating"}
    assert signals.series["operating"].values[:50].sum() == 0
    assert signals.series["operating"].values[50:].min() == 1
    assert [m.label for m in signals.markers] == ["M1"]
    listed = {topic.name: topic for topic in inventory(log)[0].topics}
    assert listed["vehicle_angular_velocity"].fields[:3] == ("xyz[0]", "xyz[1]", "xyz[2]")
    assert listed["actuator_motors"].count == SECONDS * RATE_HZ
    result = runner.invoke(app, ["inspect", str(log), "--profile", "px4_uuv"])
    assert result.exit_code == 0, result.output
    assert "ulog (profile mapping: [sources.ulog])" in result.output
    assert "ok       heave" in result.output
    assert "s on the log's clock (not a date)" in result.output


def test_a_multi_instance_topic_is_chosen_by_instance(tmp_path):
    log = _px4_log(tmp_path / "two-gyros.ulg", instances=(0, 1))
    px4 = load_profile(Path("px4_uuv"))
    with pytest.raises(LogError, match=r"2 sensor instances \(instance = 0, 1\).*where"):
        read_log(log, px4.sources)
    text = tmp_path / "px4.toml"
    profile_source, _ = profile_text(Path("px4_uuv"))
    text.write_text(profile_source.replace('field = "xyz[2]" }',
                                           'field = "xyz[2]", where = { instance = 1 } }')
                    .replace('field = "xyz[0]" }', 'field = "xyz[0]", where = { instance = 1 } }')
                    .replace('field = "xyz[1]" }', 'field = "xyz[1]", where = { instance = 1 } }'))
    chosen = read_log(log, load_profile(text).sources)
    t = np.arange(int(SECONDS * RATE_HZ)) / RATE_HZ
    np.testing.assert_allclose(chosen.series["yaw_rate"].values, 0.2 * np.sin(0.5 * t),
                               atol=1e-6)


def test_a_cut_ulog_is_analysed_up_to_the_cut_and_says_so(make_log, tmp_path):
    data = make_log("paper-flow-sensor-covered", 31, "ulog").read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[:int(len(data) * 0.6) + 5])
    at = walk_framing(cut).cut_at
    assert at is not None and at <= len(data) * 0.6 + 5
    _, report = diagnose_json(cut)
    assert report["completeness"]["status"] == "partial"
    assert report["completeness"]["damage_at_byte"] == at
    assert report["duration_s"] < 120.0


def test_damaged_definitions_are_one_line_not_a_hang(make_log, tmp_path):
    data = bytearray(make_log("paper-flow-sensor-covered", 31, "ulog").read_bytes())
    data[16:400] = bytes(384)   # the formats are gone: nothing can be decoded
    bad = tmp_path / "bad.ulg"
    bad.write_bytes(bytes(data))
    result = runner.invoke(app, ["diagnose", str(bad), "--quiet"])
    assert result.exit_code == 2
    line, = result.stderr.strip().splitlines()
    assert str(bad) in line and "definitions" in line
