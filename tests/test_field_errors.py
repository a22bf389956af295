"""A profile that names a field the log does not have gets an answer that says what to write:
the field (not the signal) named, the message's fields listed closest first; a `where` on a
key that does not exist says so; several instances of one sensor are never merged silently."""

import json
import re
import shutil
from importlib import resources

import pytest
from helpers import FMT_TYPE, refit_format, rewrite_dataflash
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
PROFILE = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()


def _profile(tmp_path, old, new):
    assert old in PROFILE
    path = tmp_path / "edited.toml"
    path.write_text(PROFILE.replace(old, new))
    return path


def _refusal(log, profile):
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(profile), "--quiet"])
    assert result.exit_code == 2 and "unexpected" not in result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and str(log) in lines[0]
    return lines[0]


@pytest.mark.parametrize(("fmt", "old", "new", "first"), [
    ("bin", 'field = "GyrZ"', 'field = "GyroZ"', "GyrZ"),
    ("tlog", 'field = "yawspeed"', 'field = "yaw_speed"', "yawspeed"),
    ("mcap", 'field = "angular_velocity.z"', 'field = "angular_velocity.zz"',
     "angular_velocity.z"),
    ("bag", 'field = "twist.linear.x"', 'field = "twist.linear.xx"', "twist.linear.x"),
    ("db3", 'field = "data[0]"', 'field = "dat[0]"', "data[0]"),
])
def test_a_misspelt_field_names_the_field_and_the_valid_ones(make_log, tmp_path, fmt, old, new,
                                                             first):
    line = _refusal(make_log("paper-normal", 11, fmt), _profile(tmp_path, old, new))
    wrong = re.search(r'field = "([^"]+)"', new).group(1)
    assert f"has no field {wrong!r}" in line
    assert re.search(r"closest first: ([^,]+)", line).group(1) == first


def test_a_where_on_a_key_that_does_not_exist_says_so(make_log, tmp_path):
    profile = _profile(tmp_path, 'where = { name = "FLOW" }', 'where = { nam = "FLOW" }')
    line = _refusal(make_log("paper-normal", 11, "tlog"), profile)
    assert "NAMED_VALUE_FLOAT has no field 'nam' (signal flow)" in line
    assert "closest first: name" in line


def _with_second_imu(source, target):
    """The DataFlash log with every IMU record followed by instance 1 of the same sensor."""
    at = 3 + 8                                                     # header, TimeUS: then I

    def change(record, kind, formats):
        if formats.get(kind) is None or formats[kind].name != "IMU":
            return record
        assert formats[kind].columns[:2] == ("TimeUS", "I")
        return record + record[:at] + b"\x01" + record[at + 1:]

    return rewrite_dataflash(source, target, change)


def test_interleaved_sensor_instances_are_refused_with_the_choice(make_log, tmp_path):
    log = _with_second_imu(make_log("paper-normal", 11, "bin"), tmp_path / "two_imus.bin")
    line = _refusal(log, _profile(tmp_path, 'field = "GyrZ"', 'field = "GyrZ"'))
    assert "IMU holds 2 sensor instances (I = 0, 1)" in line
    assert "where = { I = 0 }" in line and "merge_instances = true" in line


@pytest.mark.parametrize("choice", ['field = "GyrZ", where = { I = 1 }',
                                    'field = "GyrZ", merge_instances = true'])
def test_a_chosen_or_merged_instance_is_read(make_log, tmp_path, choice):
    log = _with_second_imu(make_log("paper-normal", 11, "bin"), tmp_path / "two_imus.bin")
    profile = _profile(tmp_path, 'field = "GyrZ"', choice)
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(profile), "--quiet"])
    assert result.exit_code == 0, result.output


def _before_instance_fields(source, target):
    """The DataFlash log as ArduPilot before 4.1 wrote it: IMU without its instance field."""
    at = 3 + 8                                                     # header, TimeUS: then I

    def change(record, kind, formats):
        if formats.get(kind) is not None and formats[kind].name == "IMU":
            return record[:at] + record[at + 1:]
        if kind == FMT_TYPE and formats.get(record[3]) is not None and \
                formats[record[3]].name == "IMU":
            return refit_format(record, (b"QB", b"TimeUS,I,"), (b"Q", b"TimeUS,"), 1)
        return record

    return rewrite_dataflash(source, target, change)


def test_the_first_instance_reads_a_log_from_before_instance_fields(make_log, tmp_path):
    new = make_log("paper-normal", 11, "bin")
    old = _before_instance_fields(new, tmp_path / "old.bin")
    first = _profile(tmp_path, 'field = "GyrZ"', 'field = "GyrZ", where = { I = 0 }')
    verdicts = []
    for log in (new, old):
        result = runner.invoke(app, ["diagnose", str(log), "--profile", str(first), "--json",
                                     str(tmp_path / f"{log.stem}.json")])
        assert result.exit_code == 0, result.output
        verdicts.append(json.loads((tmp_path / f"{log.stem}.json").read_text())["segments"])
    assert verdicts[0] == verdicts[1]
    # Another instance than the first is no such message there: the field is said missing.
    line = _refusal(old, _profile(tmp_path, 'field = "GyrZ"', 'field = "GyrZ", where = { I = 1 }'))
    assert "IMU has no field 'I' (signal yaw_rate)" in line


def _in_milliseconds(source, target):
    """The DataFlash log as ArduPilot 3.2 and before wrote it: TimeMS (ms, 32 bits) first in
    each record instead of TimeUS (µs, 64 bits)."""
    import struct

    def timed(formats, type_id):
        declared = formats.get(type_id)
        return declared is not None and declared.columns[:1] == ("TimeUS",)

    def change(record, kind, formats):
        if kind == FMT_TYPE and timed(formats, record[3]):
            return refit_format(record, (b"Q", b"TimeUS"), (b"I", b"TimeMS"), 4)
        if timed(formats, kind):
            (time_us,) = struct.unpack_from("<Q", record, 3)
            return record[:3] + struct.pack("<I", time_us // 1000) + record[11:]
        return record

    return rewrite_dataflash(source, target, change)


def test_a_log_timed_in_milliseconds_reads_the_same(make_log, tmp_path):
    new = make_log("paper-normal", 11, "bin")
    old = _in_milliseconds(new, tmp_path / "old.bin")
    reports = []
    for log in (new, old):
        result = runner.invoke(app, ["diagnose", str(log), "--json",
                                     str(tmp_path / f"{log.stem}.json")])
        assert result.exit_code == 0, result.output
        reports.append(json.loads((tmp_path / f"{log.stem}.json").read_text()))
    # The same to the millisecond its clock keeps.
    assert reports[1]["duration_s"] == pytest.approx(reports[0]["duration_s"], abs=0.002)
    assert reports[1]["verdict"] == reports[0]["verdict"]
    for ours, theirs in zip(reports[0]["segments"], reports[1]["segments"], strict=True):
        assert (theirs["name"], theirs["b"]) == (ours["name"], ours["b"])
        assert theirs["start_s"] == pytest.approx(ours["start_s"], abs=0.002)


def test_inspect_shows_the_valid_fields_of_a_misspelt_one(make_log, tmp_path):
    log = make_log("paper-normal", 11, "bin")
    shutil.copy(log, tmp_path / "log.bin")
    profile = _profile(tmp_path, 'field = "GyrZ"', 'field = "Gyr_Z"')
    result = runner.invoke(app, ["inspect", str(tmp_path / "log.bin"), "--profile",
                                 str(profile)])
    assert result.exit_code == 2
    assert "MISSING  yaw_rate" in result.stdout and "closest first: GyrZ" in result.stdout


@pytest.mark.parametrize(("fmt", "topic", "field"), [
    ("bag", "/imu/data", "angular_velocity.z"), ("db3", "/thrusters/command", "data[0]"),
    ("ros2-mcap", "/flow/velocity", "twist.linear.x"), ("mcap", "/imu/data", "header.frame_id"),
    ("tlog", "ATTITUDE", "yawspeed"), ("bin", "RCOU", "C2")])
def test_inspect_lists_every_topics_fields(make_log, fmt, topic, field):
    result = runner.invoke(app, ["inspect", str(make_log("paper-normal", 11, fmt))])
    lines = result.stdout.splitlines()
    at = next(i for i, line in enumerate(lines) if line.strip().startswith(topic + " "))
    listed = " ".join(line.strip() for line in lines[at + 1:at + 4])
    assert listed.startswith("fields") and re.search(rf"[ ,]{re.escape(field)}(,|$| )", listed)


def test_inspect_lists_instances_and_named_values(make_log, tmp_path):
    log = _with_second_imu(make_log("paper-normal", 11, "bin"), tmp_path / "two_imus.bin")
    shown = runner.invoke(app, ["inspect", str(log)]).stdout
    assert "instances I = 0, 1 (several: choose with where = { I = 0 })" in shown
    shown = runner.invoke(app, ["inspect", str(make_log("paper-normal", 11, "tlog"))]).stdout
    assert re.search(r"names\s+FLOW \(where = \{ name", shown)


def test_a_where_value_no_message_has_lists_the_values_there_are(make_log, tmp_path):
    profile = _profile(tmp_path, 'where = { name = "FLOW" }', 'where = { name = "FLOWS" }')
    line = _refusal(make_log("paper-normal", 11, "tlog"), profile)
    assert "NAMED_VALUE_FLOAT has no message with name = FLOWS; its values: FLOW" in line
