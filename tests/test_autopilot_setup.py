"""What an ArduPilot log says of its vehicle (firmware, frame, parameters), and the starting
profile `init-profile` drafts from it: a copter's outputs are its motors, one-way from the
log's PWM range, one effort group; a plane's outputs its surfaces and engine; a sub keeps
the marine draft."""

from pathlib import Path

import pytest
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from adapters.autopilot_setup import AutopilotSetup, autopilot_setup
from auvdiag_cli.cli import app
from auvdiag_cli.jobs.autopilot_outputs import output_roles
from auvdiag_cli.vehicle.profile import load_profile

runner = CliRunner()


@pytest.fixture(scope="module")
def quad_logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A simulated ArduCopter quad's flight, as its DataFlash log and its telemetry log."""
    folder = tmp_path_factory.mktemp("quad")
    logs = {}
    for fmt in ("bin", "tlog"):
        logs[fmt] = folder / f"flight.{fmt}"
        result = runner.invoke(app, ["simulate", "mission-ccw", "--profile", "arducopter_quad",
                                     "--format", fmt, "--seed", "3", "-o", str(logs[fmt])])
        assert result.exit_code == 0, result.output
    return logs


def test_a_copter_log_says_its_firmware_frame_and_parameters(quad_logs):
    setup = autopilot_setup(quad_logs["bin"], "dataflash")
    assert setup is not None and setup.vehicle == "copter"
    assert (setup.frame, setup.motors) == ("QUAD/X", 4)
    assert setup.parameter("SERVO3_FUNCTION") == 35 and setup.parameter("MOT_PWM_MAX") == 2000
    # A telemetry log without parameters: the autopilot's heartbeat (a quadrotor).
    heard = autopilot_setup(quad_logs["tlog"], "mavlink")
    assert heard is not None and (heard.vehicle, heard.motors) == ("copter", 4)
    assert "MAV_TYPE 2" in heard.evidence
    assert autopilot_setup(quad_logs["bin"], "ros") is None
    # `inspect` says it beside the span.
    shown = runner.invoke(app, ["inspect", str(quad_logs["bin"])])
    assert shown.exit_code == 0
    assert '  vehicle   copter ("ArduCopter V4.5.0' in shown.stdout and "QUAD/X" in shown.stdout


@pytest.mark.shared_data("ardusub")
def test_real_ardusub_logs_say_what_wrote_them():
    logged = autopilot_setup(SHARED_DATA / "ardusub" / "small.BIN", "dataflash")
    assert logged is not None and logged.vehicle == "sub"
    assert logged.parameter("MOT_PWM_MIN") == 1100 and len(logged.parameters) > 800
    fetched = autopilot_setup(SHARED_DATA / "ardusub" / "small.tlog", "mavlink")
    assert fetched is not None and (fetched.vehicle, fetched.frame) == ("sub", "VECTORED_6DOF")
    assert fetched.parameter("SERVO1_FUNCTION") == 33


def test_damaged_bytes_say_nothing(tmp_path):
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"\xa3\x95\x80" + bytes(range(256)) * 3)
    assert autopilot_setup(junk, "dataflash") is None
    assert autopilot_setup(tmp_path / "absent.tlog", "mavlink") is None


@pytest.mark.parametrize("fmt", ["bin", "tlog"])
def test_a_copter_is_drafted_with_its_motors_as_one_group(quad_logs, tmp_path, fmt):
    """The draft reads the motors as the shipped ArduCopter profile does (PWM 1000 … 2000 µs
    to 0 … 1, kind rotor), in one effort group, and the climb up positive; it resolves."""
    target = tmp_path / "draft.toml"
    drafted = runner.invoke(app, ["init-profile", str(quad_logs[fmt]), "--output",
                                  str(target)])
    assert drafted.exit_code == 0, drafted.output
    shown = runner.invoke(app, ["inspect", str(quad_logs[fmt]), "--profile", str(target)])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout, shown.stdout
    draft, shipped = load_profile(target), load_profile(Path("arducopter_quad"))
    family = "dataflash" if fmt == "bin" else "mavlink"
    assert draft.command_names == ("motor_1", "motor_2", "motor_3", "motor_4")
    assert {c.kind for c in draft.commands} == {"rotor"}
    for name in draft.command_names:
        ours, theirs = draft.sources[family].signals[name], shipped.sources[family].signals[name]
        assert (ours.field, ours.scale, ours.offset) == (theirs.field, pytest.approx(
            theirs.scale), pytest.approx(theirs.offset))
    assert [g.members for g in draft.effort_groups] == [draft.command_names]
    climb = next(s for s in draft.sources[family].signals.values()
                 if s.field in ("CRt", "climb"))
    assert climb.scale > 0
    assert "ArduCopter" in target.read_text() or "MAV_TYPE 2" in target.read_text()


def test_a_hexacopter_s_outputs_by_their_functions():
    """Motors where SERVOn_FUNCTION puts them (motor 1 on output 3 here), PWM from
    MOT_PWM_MIN/MAX; an output driving anything else (a camera mount) is left out."""
    functions = {"SERVO1_FUNCTION": 35, "SERVO2_FUNCTION": 36, "SERVO3_FUNCTION": 33,
                 "SERVO4_FUNCTION": 34, "SERVO5_FUNCTION": 37, "SERVO6_FUNCTION": 38,
                 "SERVO9_FUNCTION": 7, "MOT_PWM_MIN": 1100, "MOT_PWM_MAX": 1900}
    setup = AutopilotSetup("copter", "test", "HEXA/X", 6, dict(functions))
    roles = output_roles(setup, [1, 2, 3, 4, 5, 6, 9])
    assert [roles[c].name for c in sorted(roles)] == [f"motor_{k}" for k in (3, 4, 1, 2, 5, 6)]
    motor = roles[3]
    assert motor.scale * 1100 + motor.offset == pytest.approx(0.0)
    assert motor.scale * 1900 + motor.offset == pytest.approx(1.0)
    assert {r.group for r in roles.values()} == {"rotors"}
    # No parameters: ArduCopter's default, motor N on output N of the frame's motors.
    bare = output_roles(AutopilotSetup("copter", "test", None, 6), [1, 2, 7, 8])
    assert sorted(r.name for r in bare.values()) == ["motor_1", "motor_2"]
    assert "ArduCopter's defaults" in bare[1].says


def test_a_plane_s_outputs_are_its_surfaces_and_engine():
    default = output_roles(AutopilotSetup("plane", "test"), [1, 2, 3, 4])
    assert {c: (r.name, r.kind) for c, r in default.items()} == {
        1: ("aileron", "control_surface"), 2: ("elevator", "control_surface"),
        3: ("throttle", "engine"), 4: ("rudder", "control_surface")}
    throttle, aileron = default[3], default[1]
    assert throttle.scale * 1100 + throttle.offset == pytest.approx(0.0)
    assert aileron.scale * 1500 + aileron.offset == pytest.approx(0.0)
    assert aileron.scale * 1900 + aileron.offset == pytest.approx(1.0)
    # Two outputs for the ailerons act alike: a group of their own.
    two = output_roles(AutopilotSetup("plane", "test", parameters={
        "SERVO5_FUNCTION": 4, "SERVO6_FUNCTION": 4, "SERVO3_FUNCTION": 70}), [3, 5, 6])
    assert {r.name: r.group for r in two.values()} == {
        "throttle": None, "aileron_1": "ailerons", "aileron_2": "ailerons"}
    # A sub or a rover keeps the marine draft.
    assert output_roles(AutopilotSetup("sub", "test"), [1, 2]) == {}
    assert output_roles(None, [1, 2]) == {}
