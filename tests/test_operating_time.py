"""Operating time: where the profile names an operating flag (ArduSub's armed bit in the
HEARTBEAT), time when the vehicle is disarmed is neither judged nor trained on, and no onset
is placed in it. Logs: simulated dives as tlogs, their heartbeats re-encoded by pymavlink to
say disarmed over a stretch in which the vehicle is carried about by hand."""

import math
import struct
from importlib import resources

import numpy as np
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
ARMED = 128                      # MAV_MODE_FLAG_SAFETY_ARMED
OPERATING = ('operating = { message = "HEARTBEAT", field = "base_mode", bits = 128, '
             'where = { type = "12" } }')


@pytest.fixture(scope="module")
def armed_profile(tmp_path_factory):
    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    header = '[sources.mavlink]\n'
    path = tmp_path_factory.mktemp("profile") / "armed.toml"
    path.write_text(text.replace(header, header + OPERATING + "\n", 1))
    return path


def _disarmed_between(source, target, start_s, end_s):
    """The tlog with heartbeats armed except in [start_s, end_s), where the yaw rate is
    what a vehicle swung about on deck shows."""
    from pymavlink.dialects.v20 import ardupilotmega as mavlink

    from adapters.mavlink import _message_names
    from adapters.mavlink_scan import index_file

    index = index_file(source, "tlog", _message_names())
    ends = np.append(index.offsets[1:], index.data.size)
    data, first_us = bytes(index.data), int(index.times_us[0])
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    parts = []
    for start, end in zip(index.offsets.tolist(), ends.tolist(), strict=True):
        (time_us,) = struct.unpack(">Q", data[start:start + 8])
        t = (time_us - first_us) / 1e6
        disarmed = start_s <= t < end_s
        message = parser.parse_char(bytearray(data[start + 8:end]))
        name = message.get_type()
        if name == "HEARTBEAT":
            message.base_mode = 0 if disarmed else ARMED
        elif name == "ATTITUDE" and disarmed:
            message.yawspeed = 2.0 * math.sin(t)
        else:
            parts.append(data[start:end])
            continue
        sender = mavlink.MAVLink(None, srcSystem=message.get_srcSystem(),
                                 srcComponent=message.get_srcComponent())
        sender.seq = message.get_seq()
        parts.append(data[start:start + 8] + bytes(message.pack(sender)))
    target.write_bytes(b"".join(parts))
    return target


def _report(log, profile=None):
    return diagnose_json(log, *(["--profile", str(profile)] if profile else []))[1]


def test_disarmed_time_is_not_judged(make_log, tmp_path, armed_profile):
    log = _disarmed_between(make_log("paper-normal", 11, "tlog"), tmp_path / "deck.tlog",
                            40.0, 80.0)
    assert _report(log)["verdict"] == "fault"          # judged like a dive: a false alarm
    report = _report(log, armed_profile)
    assert report["verdict"] == "normal"
    note = next(n for n in report["notes"] if n.startswith("not operating"))
    excluded = float(note.split(" for ")[1].split(" s of")[0])
    assert 39.0 <= excluded <= 41.5 and "2 operating stretch(es)" in note
    assert report["not_operating_s"] == pytest.approx(excluded, abs=0.05)


def test_no_onset_is_placed_in_disarmed_time(make_log, tmp_path, armed_profile):
    """The flow sensor is covered at 115 s, the moment the vehicle is armed again."""
    log = _disarmed_between(make_log("paper-flow-sensor-covered", 31, "tlog"),
                            tmp_path / "rearmed.tlog", 70.0, 115.0)
    report = _report(log, armed_profile)
    assert report["verdict"] == "fault" and report["component"] == "flow_sensor"
    assert 115.0 <= report["onset_s"] <= 117.5


def test_a_log_never_armed_is_one_line(make_log, tmp_path, armed_profile):
    log = _disarmed_between(make_log("paper-normal", 11, "tlog"), tmp_path / "never.tlog",
                            -1.0, 1e9)
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(armed_profile)])
    assert result.exit_code == 2 and "never operates" in result.output


def test_the_operating_name_is_reserved(tmp_path):
    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    path = tmp_path / "clash.toml"
    path.write_text(text.replace('name = "flow"', 'name = "operating"'))
    result = runner.invoke(app, ["inspect", "x", "--profile", str(path)])
    assert result.exit_code == 2 and "reserved for the operating flag" in result.output


def _lifted_between_two_runs(first, second, idle_s):
    """Two simulated ZA runs with ``idle_s`` between them: thrusters at neutral while the
    vehicle is lifted out and swung about (its gyro reading nonsense)."""
    import copy

    from auvdiag_cli.simulator.run import Stream

    pause_from = first.duration_s + 0.5
    resume_at = pause_from + idle_s

    def joined(a: Stream, b: Stream, idle_value, rate_hz: float) -> Stream:
        gap = [pause_from + k / rate_hz for k in range(int(idle_s * rate_hz))]
        return Stream([*a.times_s, *gap, *(t + resume_at for t in b.times_s)],
                      [*a.values, *(idle_value(t) for t in gap), *b.values])

    dive = copy.deepcopy(first)
    dive.commands = joined(first.commands, second.commands, lambda t: (0.0, 0.0), 10.0)
    dive.sensors = {
        "flow": joined(first.sensors["flow"], second.sensors["flow"], lambda t: (0.0,), 10.0),
        "yaw_rate": joined(first.sensors["yaw_rate"], second.sensors["yaw_rate"],
                           lambda t: (2.0 * math.sin(t),), 50.0)}
    dive.markers = [*first.markers, *((t + resume_at, label) for t, label in second.markers)]
    return dive


def test_idle_commands_end_operation_where_the_log_has_no_flag(tmp_path, dive_cache, profile):
    """A ROS log without an armed flag: between two runs the thrusters idle for a minute
    while the vehicle is lifted out; `[operating] idle_after_s` leaves that minute out."""
    from auvdiag_cli.simulator.writers import write_log

    dive = _lifted_between_two_runs(dive_cache("dms-za", 31), dive_cache("dms-za", 32), 60.0)
    log = tmp_path / "lifted.mcap"
    write_log(dive, profile, log, "mcap")
    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    idle = tmp_path / "idle.toml"
    idle.write_text(text + "\n[operating]\nidle_after_s = 3.0\n")
    assert _report(log)["verdict"] == "fault"             # the lifted minute, judged
    report = _report(log, idle)
    assert report["verdict"] == "normal", report["notes"]
    # idle from 3 s after each ZA's last 5 s at neutral: 28 s to the resume (62.6 s), and
    # the last 2 s of the second run
    assert report["not_operating_s"] == pytest.approx(64.6, abs=0.3)
