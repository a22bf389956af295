"""Vehicles modelled from their controllers' set points, drafted from logs whose set point and
measurement sit in two messages. `init-profile --closed-loop` on a PX4 ULog pairs the rate
controller's set points (`vehicle_rates_setpoint`) with the gyro rates
(`vehicle_angular_velocity`) and the velocity set points with the estimate; on an ArduPilot
telemetry log, the attitude its controller targets (`NAV_CONTROLLER_OUTPUT`, degrees) with
`ATTITUDE` (rad). The motor outputs are read for the effort check only.
ULogs written here: a quadrotor's rate and vertical-speed loops following stepped set points
(first-order lags, noise), its four motors mixing what the loops ask; from 60 s one flight's
yaw answers its set point at 40 % of the normal gain. Telemetry logs written by pymavlink,
mavros bags by rosbags."""

from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_json
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.simulator.writers.ros import RosMessages, _assign, _open_rosbag_writer
from auvdiag_cli.simulator.writers.ulog import UlogTopic, write_ulog_file
from auvdiag_cli.vehicle.profile import load_profile

RATE_HZ = 50
LAGS_S = np.array([0.08, 0.08, 0.15, 0.5])        # roll, pitch, yaw rate; vertical speed
X_MIX = np.array([[-1, 1, 1], [1, -1, 1], [1, 1, -1], [-1, -1, -1]], float)
SET_POINTS = ("roll_rate_set_point", "pitch_rate_set_point", "yaw_rate_set_point",
              "heave_set_point")
MEASURED = ("roll_rate", "pitch_rate", "yaw_rate", "heave")
MOTORS = ("motor_1", "motor_2", "motor_3", "motor_4")


def quaternions(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(samples, 4): w, x, y, z of the Z-Y-X attitudes."""
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def write_px4_flight(path: Path, seed: int, seconds: float = 120.0,
                     yaw_weak_from_s: float | None = None) -> Path:
    """A flight as PX4 logs it; the north-speed set point is unset (NaN) for its first half,
    as PX4 leaves it while it holds a position."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, seconds, 1 / RATE_HZ)
    steps = np.repeat(rng.uniform(-0.4, 0.4, (t.size // 100 + 1, 4)), 100, axis=0)[:t.size]
    set_point = np.zeros_like(steps)
    answer = np.zeros_like(steps)
    gain = np.ones_like(steps)
    if yaw_weak_from_s is not None:
        gain[t >= yaw_weak_from_s, 2] = 0.4
    for k in range(1, t.size):
        set_point[k] = set_point[k - 1] + (steps[k] - set_point[k - 1]) / 10
        answer[k] = answer[k - 1] + (gain[k - 1] * set_point[k - 1] - answer[k - 1]) / (
            LAGS_S * RATE_HZ)
    answer += rng.normal(0, 0.01, answer.shape)
    motors = (0.55 + 0.5 * set_point[:, 3:] + 0.4 * (set_point[:, :3] - answer[:, :3]) @ X_MIX.T
              + rng.normal(0, 0.01, (t.size, 4)))
    us = (1_000_000 + t * 1e6).astype(np.int64)
    north = np.where(t >= seconds / 2, 0.5 * np.sin(t / 7), np.nan)
    write_ulog_file(path, [
        UlogTopic("vehicle_rates_setpoint", ("roll", "pitch", "yaw", "thrust_body[2]"), us,
                  np.column_stack([set_point[:, :3], -0.5 - 0.1 * set_point[:, 3]])),
        UlogTopic("vehicle_angular_velocity", ("xyz[0]", "xyz[1]", "xyz[2]"), us + 100,
                  answer[:, :3]),
        UlogTopic("vehicle_local_position_setpoint", ("vx", "vz"), us[::5],
                  np.column_stack([north, set_point[:, 3]])[::5]),
        UlogTopic("vehicle_local_position", ("vx", "vz"), us[::5] + 200,
                  np.column_stack([np.nan_to_num(north), answer[:, 3]])[::5]),
        UlogTopic("actuator_motors", tuple(f"control[{i}]" for i in range(4)), us + 300, motors),
        UlogTopic("actuator_armed", ("armed",), us[::50], np.ones((us[::50].size, 1))),
    ], 900_000)
    return path


def invoke(*arguments: str) -> str:
    result = CliRunner().invoke(app, list(arguments))
    assert result.exit_code == 0, result.output
    return result.output


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("px4_flights")
    for seed in range(4):
        write_px4_flight(folder / f"normal_{seed}.ulg", seed)
    write_px4_flight(folder / "later_normal.ulg", 40)
    write_px4_flight(folder / "yaw_weak.ulg", 41, yaw_weak_from_s=60.0)
    invoke("init-profile", str(folder / "normal_0.ulg"), "--closed-loop", "--output",
           str(folder / "px4.toml"))
    return folder


def test_the_set_points_drive_the_draft_and_what_was_measured_beside_them_is_judged(
        flights: Path):
    profile = load_profile(flights / "px4.toml")
    assert profile.command_names == SET_POINTS          # not the half-unset north speed
    assert all(c.kind == "set_point" for c in profile.commands)
    assert set(MEASURED) <= set(profile.sensor_names)
    assert [profile.sensor(n).unit for n in MEASURED] == ["rad/s"] * 3 + ["m/s"]
    signals = profile.sources["ulog"].signals
    assert (signals["yaw_rate_set_point"].topic, signals["yaw_rate_set_point"].field) == (
        "vehicle_rates_setpoint", "yaw")
    assert (signals["yaw_rate"].topic, signals["yaw_rate"].field) == (
        "vehicle_angular_velocity", "xyz[2]")
    # PX4 numbers its motors from 1; they are read for the effort check only.
    assert profile.output_names == MOTORS
    assert signals["motor_1"].field == "control[0]"
    assert [sorted(g.members) for g in profile.effort_groups] == [list(MOTORS)]
    shown = invoke("inspect", str(flights / "later_normal.ulg"), "--profile",
                   str(flights / "px4.toml"))
    assert "MISSING" not in shown


def test_without_closed_loop_no_set_point_is_taken_for_a_measurement(flights: Path,
                                                                     tmp_path: Path):
    invoke("init-profile", str(flights / "normal_0.ulg"), "--output", str(tmp_path / "p.toml"))
    text = (tmp_path / "p.toml").read_text()
    profile = load_profile(tmp_path / "p.toml")
    assert profile.command_names == MOTORS and not profile.output_names
    assert set(MEASURED) <= set(profile.sensor_names)
    assert "_setpoint" not in text and "thrust_body" not in text


@pytest.mark.slow    # trains a model
def test_a_loop_that_stops_following_its_set_point_is_found_where_it_began(flights: Path):
    model = flights / "model"
    invoke("train", *(str(flights / f"normal_{s}.ulg") for s in range(4)), "--profile",
           str(flights / "px4.toml"), "--output", str(model), "--iterations-scale", "0.02",
           "--hidden", "8", "--predictor", "linear")
    code, report = diagnose_json(flights / "later_normal.ulg", "--profile",
                                 str(flights / "px4.toml"), "--model", str(model))
    assert (code, report["verdict"]) == (0, "normal"), report
    code, report = diagnose_json(flights / "yaw_weak.ulg", "--profile",
                                 str(flights / "px4.toml"), "--model", str(model))
    assert (code, report["verdict"]) == (1, "fault"), report
    assert report["b"]["yaw_rate"] == 1
    assert [s for s, bit in report["b"].items() if bit] == ["yaw_rate"]
    assert 58.0 <= report["onset_s"] <= 62.0 and 60.0 <= report["detected_at_s"] <= 64.0


def write_telemetry(path: Path, seed: int, seconds: float = 60.0) -> Path:
    """An ArduPilot vehicle's telemetry as a ground station records it (pymavlink): the
    targeted roll and pitch at 2 Hz, the attitude at 10 Hz following them, four outputs, an
    armed heartbeat each second."""
    rng = np.random.default_rng(seed)
    vehicle = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    t = np.arange(0, seconds, 0.1)
    target = np.repeat(rng.uniform(-15, 15, (t.size // 30 + 1, 2)), 30, axis=0)[:t.size]
    attitude = np.zeros_like(target)
    for k in range(1, t.size):
        attitude[k] = attitude[k - 1] + (np.radians(target[k - 1]) - attitude[k - 1]) / 4
    rates = np.gradient(attitude, 0.1, axis=0)
    frames = []
    for k, time in enumerate(t):
        stamp = int(1_700_000_000e6 + time * 1e6)
        if k % 10 == 0:
            frames.append((stamp, vehicle.heartbeat_encode(12, 3, 209, 19, 4)))
        if k % 5 == 0:
            frames.append((stamp, vehicle.nav_controller_output_encode(
                *target[k], 0, 0, 0, 0.0, 0.0, 0.0)))
        frames.append((stamp, vehicle.attitude_encode(int(time * 1000), *attitude[k], 0.0,
                                                      *rates[k], 0.0)))
        outputs = 1500 + (200 * np.array([1, -1, 1, -1]) * (attitude[k, 0] - attitude[k, 1])
                          + rng.normal(0, 5, 4)).astype(int)
        frames.append((stamp, vehicle.servo_output_raw_encode(int(time * 1e6), 0, *outputs,
                                                              1500, 1500, 1500, 1500)))
    path.write_bytes(b"".join(stamp.to_bytes(8, "big") + bytes(frame.pack(vehicle))
                              for stamp, frame in frames))
    return path


def test_a_telemetry_log_drafts_the_attitude_loops_from_its_targets(tmp_path: Path):
    log = write_telemetry(tmp_path / "dive.tlog", 3)
    invoke("init-profile", str(log), "--closed-loop", "--output", str(tmp_path / "sub.toml"))
    profile = load_profile(tmp_path / "sub.toml")
    assert profile.command_names == ("nav_roll", "nav_pitch")
    assert all(c.kind == "set_point" for c in profile.commands)
    signals = profile.sources["mavlink"].signals
    # The targets in degrees, the attitude in radians: each in the one unit they share.
    assert signals["nav_roll"].scale == pytest.approx(np.radians(1.0))
    assert signals["roll"].scale == 1.0 and profile.sensor("roll").unit == "rad"
    assert {(t.set_point, t.measured, t.rate) for t in profile.tracking} == {
        ("nav_roll", "roll", "rollspeed"), ("nav_pitch", "pitch", "pitchspeed")}
    assert len(profile.output_names) == 4
    assert "MISSING" not in invoke("inspect", str(log), "--profile", str(tmp_path / "sub.toml"))


@pytest.mark.shared_data("ardusub")
def test_a_closed_loop_draft_of_a_real_ardusub_telemetry_log(tmp_path: Path):
    log = SHARED_DATA / "ardusub" / "small.tlog"
    invoke("init-profile", str(log), "--closed-loop", "--output", str(tmp_path / "sub.toml"))
    profile = load_profile(tmp_path / "sub.toml")
    assert profile.command_names == ("nav_roll", "nav_pitch")
    assert {"roll", "pitch", "rollspeed", "pitchspeed"} <= set(profile.sensor_names)
    assert "MISSING" not in invoke("inspect", str(log), "--profile", str(tmp_path / "sub.toml"))


ATTITUDE_TARGET = ("std_msgs/Header header\nuint8 type_mask\ngeometry_msgs/Quaternion "
                   "orientation\ngeometry_msgs/Vector3 body_rate\nfloat32 thrust\n")


def write_mavros_bag(path: Path, namespace: str, seed: int) -> Path:
    """A PX4 vehicle as mavros records it under ``namespace``: ATTITUDE_TARGET's body rates
    and attitude at 50 Hz, the IMU's rates and attitude following them, the motor outputs,
    the armed state."""
    from rosbags.typesys import get_types_from_msg

    rng = np.random.default_rng(seed)
    types = {"setpoint_raw/target_attitude": "mavros_msgs/msg/AttitudeTarget",
             "imu/data": "sensor_msgs/msg/Imu", "rc/out": "mavros_msgs/msg/RCOut",
             "state": "mavros_msgs/msg/State"}
    messages = RosMessages(True, {})
    messages.store.register(get_types_from_msg(ATTITUDE_TARGET, types[
        "setpoint_raw/target_attitude"]))
    t = np.arange(0, 30, 0.02)
    asked = np.repeat(rng.uniform(-0.5, 0.5, (t.size // 50 + 1, 3)), 50, axis=0)[:t.size]
    rates = np.zeros_like(asked)
    for k in range(1, t.size):
        rates[k] = rates[k - 1] + (asked[k - 1] - rates[k - 1]) / 4
    aimed = quaternions(0.3 * np.sin(t / 3), 0.2 * np.sin(t / 4), 0.1 * t)
    held = np.vstack([aimed[:10], aimed[:-10]])          # the attitude 0.2 s behind its target
    with _open_rosbag_writer(path, "bag") as writer:
        connections = {name: writer.add_connection(f"{namespace}/mavros/{name}", msgtype,
                                                   typestore=messages.store)
                       for name, msgtype in types.items()}
        for k, time in enumerate(t):
            stamp = 1_700_000_000 * 10**9 + int(time * 1e9)
            fields = {"setpoint_raw/target_attitude": {
                          **{f"body_rate.{a}": asked[k, i] for i, a in enumerate("xyz")},
                          **{f"orientation.{a}": aimed[k, i] for i, a in enumerate("wxyz")}},
                      "imu/data": {
                          **{f"angular_velocity.{a}": rates[k, i] + rng.normal(0, 0.01)
                             for i, a in enumerate("xyz")},
                          **{f"orientation.{a}": held[k, i] for i, a in enumerate("wxyz")}},
                      "rc/out": {f"channels[{i}]": 1600 + int(200 * mix + rng.normal(0, 20))
                                 for i, mix in enumerate(X_MIX @ asked[k])},
                      "state": {"armed": 1.0}}
            for name, values in fields.items():
                message = messages.zero(types[name])
                for field, value in values.items():
                    _assign(message, field, value)
                writer.write(connections[name], stamp, messages.store.serialize_ros1(
                    message, types[name]))
    return path


def test_a_mavros_bag_drafts_the_attitude_target_beside_the_imu(tmp_path: Path):
    """Under a namespace, as a vehicle among several records it. Before, a mavros bag's
    draft had no command it recognised and took its headers' stamps for commands."""
    log = write_mavros_bag(tmp_path / "flight.bag", "/uav1", 5)
    invoke("init-profile", str(log), "--closed-loop", "--output", str(tmp_path / "p.toml"))
    profile = load_profile(tmp_path / "p.toml")
    axes = [f"angular_velocity_{a}" for a in "xyz"]
    assert set(profile.command_names) == {f"{a}_set_point" for a in [*axes, "roll", "pitch"]}
    assert all(c.kind == "set_point" for c in profile.commands)
    assert {*axes, "roll", "pitch"} <= set(profile.sensor_names)
    # mavros logs the attitude as a quaternion only: roll and pitch read from it, their
    # loops with the IMU's rates about the same axes.
    assert {(t.set_point, t.measured, t.rate) for t in profile.tracking} == {
        ("roll_set_point", "roll", "angular_velocity_x"),
        ("pitch_set_point", "pitch", "angular_velocity_y")}
    signals = profile.sources["ros"].signals
    assert (signals["angular_velocity_z_set_point"].topic,
            signals["angular_velocity_z_set_point"].field) == (
        "/uav1/mavros/setpoint_raw/target_attitude", "body_rate.z")
    # mavros's rc/out is the autopilot's outputs, numbered as ArduPilot numbers them.
    assert profile.output_names == ("servo1", "servo2", "servo3", "servo4")
    assert (signals["servo1"].field, signals["servo1"].scale) == ("channels[0]", 0.0025)
    assert "MISSING" not in invoke("inspect", str(log), "--profile", str(tmp_path / "p.toml"))
    # Without it, the outputs are the commands; the attitude target is neither a measurement
    # nor an actuator, and no header (sequence number, stamp) is either.
    invoke("init-profile", str(log), "--output", str(tmp_path / "plain.toml"))
    plain = load_profile(tmp_path / "plain.toml")
    assert plain.command_names == ("servo1", "servo2", "servo3", "servo4")
    assert set(plain.sensor_names) == {*axes, "roll", "pitch"}
    assert "target_attitude" not in (tmp_path / "plain.toml").read_text()


def test_a_px4_attitude_reads_from_its_quaternion_and_its_target_drives_the_draft(
        tmp_path: Path):
    """PX4 logs the attitude and the attitude its controller targets as quaternions only
    (`vehicle_attitude` `q`, `vehicle_attitude_setpoint` `q_d`, w first)."""
    from adapters import read_log
    from adapters.signals import FieldSource, LogSources

    t = np.arange(0, 60, 0.02)
    angles = np.column_stack([0.4 * np.sin(t / 3), 0.3 * np.sin(t / 5 + 1), 2.5 * np.sin(t / 7)])
    target = quaternions(*angles.T)
    us = (1_000_000 + t * 1e6).astype(np.int64)
    log = tmp_path / "flight.ulg"
    write_ulog_file(log, [
        UlogTopic("vehicle_attitude_setpoint", tuple(f"q_d[{i}]" for i in range(4)), us,
                  target),
        UlogTopic("vehicle_attitude", tuple(f"q[{i}]" for i in range(4)), us + 50,
                  np.vstack([target[:10], target[:-10]])),
        UlogTopic("vehicle_angular_velocity", ("xyz[0]", "xyz[1]", "xyz[2]"), us + 100,
                  np.gradient(angles, 0.02, axis=0)),
        UlogTopic("actuator_motors", tuple(f"control[{i}]" for i in range(4)), us + 200,
                  0.5 + 0.1 * np.sin(t / 2)[:, None] + np.zeros((t.size, 4)))], 900_000)
    paths = tuple(f"q_d[{i}]" for i in range(4))
    read = read_log(log, {"ulog": LogSources({
        angle: FieldSource("vehicle_attitude_setpoint", paths[0], quaternion=paths,
                           angle=angle) for angle in ("roll", "pitch", "yaw")})}).series
    for k, angle in enumerate(("roll", "pitch", "yaw")):
        assert read[angle].values == pytest.approx(angles[:, k], abs=1e-6)
    invoke("init-profile", str(log), "--closed-loop", "--output", str(tmp_path / "p.toml"))
    profile = load_profile(tmp_path / "p.toml")
    assert profile.command_names == ("roll_set_point", "pitch_set_point")
    assert {"roll", "pitch"} <= set(profile.sensor_names) and profile.sensor("roll").unit == "rad"
    assert {(t.set_point, t.measured, t.rate) for t in profile.tracking} == {
        ("roll_set_point", "roll", "roll_rate"), ("pitch_set_point", "pitch", "pitch_rate")}
    shown = invoke("inspect", str(log), "--profile", str(tmp_path / "p.toml"))
    assert "roll of q[0] q[1] q[2] q[3]" in shown and "MISSING" not in shown
    # The simulator writes a field a signal; it says so rather than write a wrong log.
    from auvdiag_cli.vehicle.profile import profile_text

    text, _ = profile_text()
    (tmp_path / "tb.toml").write_text(text.replace(
        'yaw_rate = { message = "vehicle_angular_velocity", field = "xyz[2]" }',
        'yaw_rate = { message = "vehicle_attitude", quaternion = ["q[0]", "q[1]", "q[2]", '
        '"q[3]"], angle = "yaw" }'))
    refused = CliRunner().invoke(app, ["simulate", "paper-normal", "--profile",
                                       str(tmp_path / "tb.toml"), "--format", "ulog",
                                       "--output", str(tmp_path / "sim.ulg")])
    assert refused.exit_code == 2 and "from a quaternion" in refused.output


@pytest.mark.parametrize(("entry", "words"), [
    ('{ message = "a", quaternion = ["q[0]", "q[1]", "q[2]"], angle = "roll" }',
     "must list the paths of its w, x, y and z"),
    ('{ message = "a", quaternion = ["q[0]", "q[1]", "q[2]", "q[3]"], angle = "heading" }',
     "must be one of roll, pitch, yaw"),
    ('{ message = "a", field = "q[0]", quaternion = ["q[0]", "q[1]", "q[2]", "q[3]"], '
     'angle = "roll" }', "has no field"),
])
def test_a_quaternion_source_says_what_is_wrong_with_it(tmp_path: Path, entry: str,
                                                         words: str):
    from auvdiag_cli.vehicle.profile import profile_text
    from auvdiag_errors import ProfileError

    text, _ = profile_text(Path("px4_uuv"))
    path = tmp_path / "p.toml"
    path.write_text(text.replace('heave = { message = "vehicle_local_position", field = "vz" }',
                                 f"heave = {entry}"))
    with pytest.raises(ProfileError, match=words):
        load_profile(path)


@pytest.mark.shared_data("alfa")
def test_a_real_aircraft_attitude_from_its_quaternion_matches_its_autopilot(tmp_path: Path):
    """ALFA 2018-09-11-14-41-38 (folder and bag): `/mavros/imu/data` `orientation` as roll and
    pitch against the angles ArduPlane reports (`nav_info` `measured`, degrees); ROS's pitch
    is nose down positive."""
    from adapters import read_log
    from adapters.signals import FieldSource, LogSources

    folder = SHARED_DATA / "alfa" / "carbonZ_2018-09-11-14-41-38_no_failure"
    paths = tuple(f"orientation.{part}" for part in "wxyz")
    sources = LogSources({
        **{angle: FieldSource("/mavros/imu/data", paths[0], quaternion=paths, angle=angle)
           for angle in ("roll", "pitch")},
        **{f"said_{angle}": FieldSource(f"/mavros/nav_info/{angle}", "measured",
                                        scale=np.radians(1.0)) for angle in ("roll", "pitch")}})
    for log in (folder, next(folder.glob("*.bag"))):
        series = read_log(log, {"ros": sources}).series
        for angle, sign, within in (("roll", 1, 0.04), ("pitch", -1, 0.02)):
            said = series[f"said_{angle}"]
            ours = np.interp(said.times_ns, series[angle].times_ns, series[angle].values)
            assert np.sqrt(np.mean((sign * ours - said.values) ** 2)) < within
