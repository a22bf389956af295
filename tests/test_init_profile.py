"""`auvdiag init-profile`: a starting profile drafted from a log loads, and every signal it
proposes resolves on that log; what the log cannot tell is marked CHECK."""

import math
import tomllib
import warnings
from pathlib import Path

import pytest
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
# (format, a command the draft must propose, a sensor it must propose)
EXPECTED = [("tlog", "servo1_raw", "yawspeed"), ("bin", "c1", "gyrz"),
            ("mcap", "data_0", "angular_velocity_z"), ("bag", "data_1", "angular_velocity_z"),
            ("csv", "thruster_0", "yaw_rate_rps")]


def _draft_and_inspect(log, target):
    drafted = runner.invoke(app, ["init-profile", str(log), "--output", str(target)])
    assert drafted.exit_code == 0, drafted.output
    shown = runner.invoke(app, ["inspect", str(log), "--profile", str(target)])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout, shown.stdout
    return target.read_text()


@pytest.mark.parametrize(("fmt", "command", "sensor"), EXPECTED)
def test_the_draft_loads_and_resolves_on_its_log(make_log, tmp_path, fmt, command, sensor):
    text = _draft_and_inspect(make_log("paper-normal", 11, fmt), tmp_path / "draft.toml")
    assert f'[[commands]]\nname = "{command}"' in text
    assert f'[[sensors]]\nname = "{sensor}"' in text
    assert "CHECK" in text


def test_an_existing_file_is_not_overwritten(make_log, tmp_path):
    target = tmp_path / "mine.toml"
    target.write_text("# my own work\n")
    result = runner.invoke(app, ["init-profile", str(make_log("paper-normal", 11, "tlog")),
                                 "--output", str(target)])
    assert result.exit_code == 2 and "exists already" in result.output
    assert target.read_text() == "# my own work\n"


def test_a_log_with_nothing_that_moves_is_one_line(tmp_path):
    log = tmp_path / "still.csv"
    log.write_text("time,pwm1,depth\n" + "".join(f"{t},1100,0.5\n" for t in range(50)))
    result = runner.invoke(app, ["init-profile", str(log)])
    assert result.exit_code == 2 and "found no command" in result.output


def test_a_field_of_huge_values_is_drafted_without_a_warning(tmp_path):
    # A damaged log's field read as ±1e300 (found by fuzzing a db3): its spread overflowed
    # and NumPy printed a warning among the command's output.
    log = tmp_path / "huge.csv"
    log.write_text("time,pwm1,yaw_rate\n" + "".join(
        f"{t / 10},{1e300 if t % 2 else -1e300},{math.sin(t / 10):.3f}\n" for t in range(200)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = runner.invoke(app, ["init-profile", str(log)])
    assert result.exit_code == 0, result.output
    assert "pwm1" in result.output and "yaw_rate" in result.output


@pytest.mark.shared_data("ardusub")
@pytest.mark.shared_data("haizhe/train")
@pytest.mark.parametrize("relative", ["ardusub/small.tlog", "ardusub/small.BIN",
                                      "haizhe/train/Normal/Normal_0.csv"])
def test_drafts_from_real_logs_resolve(tmp_path, relative):
    text = _draft_and_inspect(SHARED_DATA / relative, tmp_path / "real.toml")
    if relative.endswith(".tlog"):     # the autopilot's armed bit, not a companion's
        assert 'operating = { message = "HEARTBEAT", field = "base_mode", where = { type = ' \
               '"12" }, bits = 128 }' in text
    if relative.endswith(".csv"):
        assert 'time = { column = "time", unit = "hhmmss" }' in text


def test_like_a_profile_moves_what_does_not_read_to_the_closest_field(make_log, tmp_path):
    from importlib import resources

    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    like = tmp_path / "like.toml"
    like.write_text(text.replace('field = "servo2_raw"', 'field = "servo_2_raw"')
                    .replace('field = "yawspeed"', 'field = "yaw_speed"'))
    log = make_log("paper-normal", 11, "tlog")
    draft = _draft_and_inspect_like(log, like, tmp_path / "fitted.toml")
    assert "# 2 of 4 signals read on the log as that profile maps them." in draft
    assert "moved to the closest field: thruster_1: SERVO_OUTPUT_RAW servo_2_raw -> " \
           "servo2_raw" in draft
    assert "yaw_rate: ATTITUDE yaw_speed -> yawspeed" in draft


def _draft_and_inspect_like(log, like, target):
    drafted = runner.invoke(app, ["init-profile", str(log), "--like", str(like),
                                  "--output", str(target)])
    assert drafted.exit_code == 0, drafted.output
    shown = runner.invoke(app, ["inspect", str(log), "--profile", str(target)])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout, shown.stdout
    return target.read_text()


@pytest.mark.shared_data("ardusub")
def test_like_bluerov2_on_real_logs(tmp_path):
    log = SHARED_DATA / "ardusub" / "small.BIN"
    draft = _draft_and_inspect_like(log, Path("bluerov2_standard"), tmp_path / "rov.toml")
    assert "# 11 of 11 signals read on the log as that profile maps them." in draft
    result = runner.invoke(app, ["init-profile", str(SHARED_DATA / "ardusub" / "small.tlog"),
                                 "--like", "bluerov2"])          # the DVL is not there
    assert result.exit_code == 2 and "surge" in result.output and "draft without --like" \
        in result.output


@pytest.mark.shared_data("ardusub")
def test_a_closed_loop_draft_of_a_real_ardusub_log(tmp_path):
    """--closed-loop on a real ArduSub DataFlash log: the controller's attitude and rate set
    points drive the model, in SI units like what it measured beside each (a sensor), and
    the thruster outputs are read for the effort check only; the draft resolves."""
    from auvdiag_cli.vehicle.profile import load_profile

    log = SHARED_DATA / "ardusub" / "small.BIN"
    drafted = runner.invoke(app, ["init-profile", str(log), "--closed-loop",
                                  "--output", str(tmp_path / "sub.toml")])
    assert drafted.exit_code == 0, drafted.output
    shown = runner.invoke(app, ["inspect", str(log), "--profile", str(tmp_path / "sub.toml")])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout, shown.stdout
    profile = load_profile(tmp_path / "sub.toml")
    assert {"att_desroll", "rate_rdes", "rate_ydes"} <= set(profile.command_names)
    assert all(c.kind == "set_point" for c in profile.commands)
    assert {"att_roll", "rate_r", "rate_y"} <= set(profile.sensor_names)
    assert profile.sensor("rate_r").unit == "rad/s" and profile.sensor("att_roll").unit == "rad"
    desired = profile.sources["dataflash"].signals["rate_rdes"]
    assert (desired.topic, desired.field, desired.scale) == ("RATE", "RDes",
                                                             pytest.approx(0.0174533))
    assert profile.output_names and all(
        profile.sources["dataflash"].signals[n].topic == "RCOU" for n in profile.output_names)
    # The attitude loops, whose gain the change test judges, with their rates.
    assert {(t.set_point, t.measured, t.rate) for t in profile.tracking} == {
        ("att_desroll", "att_roll", "rate_r"), ("att_despitch", "att_pitch", "rate_p")}
    # Without it, the same log is drafted from its thruster outputs, as before.
    plain = runner.invoke(app, ["init-profile", str(log)])
    assert plain.exit_code == 0 and "[[outputs]]" not in plain.stdout
    assert "RATE" not in plain.stdout


@pytest.mark.shared_data("ardusub")
def test_the_thrusters_of_a_real_bluerov2_heavy_telemetry_log_are_grouped_by_their_job():
    """Eight thrusters at like levels, no parameters in the log: the draft groups those
    that move together, the four horizontal (outputs 1-4) and the four vertical (5-8); the
    camera mount and lights (12, 13) in none. By their levels alone, seven were one group."""
    from auvdiag_cli.jobs.profile_draft import draft_profile

    text = draft_profile(SHARED_DATA / "ardusub" / "small.tlog", "heavy")
    groups = sorted(sorted(line.split("=", 1)[1].strip(' []').replace('"', "").split(", "))
                    for line in text.splitlines() if line.startswith("actuators ="))
    assert groups == [[f"servo{n}_raw" for n in (1, 2, 3, 4)],
                      [f"servo{n}_raw" for n in (5, 6, 7, 8)]]


def test_closed_loop_needs_set_points_and_no_like(make_log):
    log = make_log("paper-normal", 11)
    refused = runner.invoke(app, ["init-profile", str(log), "--closed-loop"])
    assert refused.exit_code == 2 and "found no controller set point" in refused.output
    both = runner.invoke(app, ["init-profile", str(log), "--closed-loop", "--like",
                               "twin_burger"])
    assert both.exit_code == 2 and "--closed-loop drafts from the log" in both.output


def test_a_csv_whose_sensor_names_are_unknown_gets_every_varying_column_to_check(tmp_path):
    """Columns named as a Crazyflie logs them (stateEstimate_vz, a clock in µs since boot):
    no sensor is recognised by name, so every column that varies is proposed, marked CHECK;
    the clock's unit comes from its name; inspect without a profile shows the span."""
    from typer.testing import CliRunner

    from auvdiag_cli.cli import app
    from auvdiag_cli.vehicle.profile import load_profile

    log, draft = tmp_path / "flight.csv", tmp_path / "draft.toml"
    rows = ["time_us,motor_m1,motor_m2,stateEstimate_vz,stateEstimate_az,constant"]
    rows += [f"{9_000_000 + 10_000 * k},{30000 + 50 * (k % 7)},{30000 + 40 * (k % 5)},"
             f"{0.01 * (k % 11)},{0.1 * (k % 3)},5" for k in range(400)]
    log.write_text("\n".join(rows) + "\n")
    runner = CliRunner()
    result = runner.invoke(app, ["init-profile", str(log), "--output", str(draft)])
    assert result.exit_code == 0, result.output
    text = draft.read_text()
    assert 'time = { column = "time_us", unit = "us" }' in text
    assert text.count("CHECK: not recognised by its name") == 2
    profile = load_profile(draft)
    assert profile.sensor_names == ("stateestimate_vz", "stateestimate_az")
    shown = runner.invoke(app, ["inspect", str(log)])      # no profile: described only
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout
    assert "profile signals: not checked" in shown.stdout
    assert "span      9.000 … 12.990 s on the log's clock (not a date)  (4.0 s)" in shown.stdout
    assert "clock: column time_us read in us (guessed" in shown.stdout
    checked = runner.invoke(app, ["inspect", str(log), "--profile", "twin_burger"])
    assert checked.exit_code == 2 and "MISSING" in checked.stdout


def test_a_csv_whose_command_names_are_unknown_proposes_the_held_columns_as_commands(
        tmp_path):
    """No column is named like a command: the ones that hold their value between changes
    (a set point stepped every two seconds) are proposed as commands, the noisy ones as
    sensors, each marked CHECK; the draft loads and resolves on its log."""
    import numpy as np

    from auvdiag_cli.vehicle.profile import load_profile

    rng = np.random.default_rng(3)
    steps = 600
    level = np.repeat(rng.uniform(-1, 1, steps // 20 + 1), 20)[:steps]
    speed = np.convolve(level, np.ones(15) / 15, "same") + rng.normal(0, 0.02, steps)
    log, draft = tmp_path / "run.csv", tmp_path / "draft.toml"
    rows = ["time,setpoint,speed_over_ground_xyz,heading_noise"]
    rows += [f"{0.1 * k:.1f},{level[k]:.3f},{speed[k]:.4f},{rng.normal():.4f}"
             for k in range(steps)]
    log.write_text("\n".join(rows) + "\n")
    text = _draft_and_inspect(log, draft)
    assert text.count("proposed as a command because it holds its value") == 1
    profile = load_profile(draft)
    assert profile.command_names == ("setpoint",)
    assert set(profile.sensor_names) == {"speed_over_ground_xyz", "heading_noise"}


def test_a_log_with_set_points_is_drafted_as_a_closed_loop_with_outputs(tmp_path):
    """Set points and motor outputs in one log: the set points drive the model, the motors
    are outputs read for the effort check only, grouped as acting alike."""
    import numpy as np

    from auvdiag_cli.vehicle.profile import load_profile

    rng = np.random.default_rng(5)
    steps = 800
    roll = np.repeat(rng.uniform(-0.3, 0.3, steps // 40 + 1), 40)[:steps]
    collective = 0.1 * np.sin(np.arange(steps) / 30)      # the rotors share the lift
    motors = 0.5 + collective[:, None] + 0.02 * rng.standard_normal((steps, 4))
    log, draft = tmp_path / "flight.csv", tmp_path / "draft.toml"
    rows = ["time,roll_commanded,motor_1,motor_2,motor_3,motor_4,roll_rate"]
    rows += [f"{0.05 * k:.2f},{roll[k]:.3f}," + ",".join(f"{m:.4f}" for m in motors[k])
             + f",{rng.normal(0, 0.1):.4f}" for k in range(steps)]
    log.write_text("\n".join(rows) + "\n")
    text = _draft_and_inspect(log, draft)
    assert "[[outputs]]" in text and "move an output to [[commands]]" in text
    profile = load_profile(draft)
    assert profile.command_names == ("roll_commanded",)
    assert profile.commands[0].kind == "set_point"
    assert profile.output_names == ("motor_1", "motor_2", "motor_3", "motor_4")
    assert [sorted(g.members) for g in profile.effort_groups] == [list(profile.output_names)]


def test_the_documented_minimal_profile_loads_and_reads_a_log(tmp_path):
    """The tutorial's complete minimal profile is a working profile, not a sketch."""
    from auvdiag_cli.vehicle.profile import load_profile

    readme = (Path(__file__).resolve().parents[1] / "docs" / "vehicles.md").read_text()
    start = readme.index("A complete minimal profile")
    block = readme[readme.index("```toml\n", start) + 8:readme.index("```\n", start + 30)]
    profile_path = tmp_path / "minimal.toml"
    profile_path.write_text(block)
    profile = load_profile(profile_path)
    assert (profile.command_names, profile.sensor_names) == (("thrust",), ("speed",))
    log = tmp_path / "run.csv"
    log.write_text("t,cmd,speed\n" + "".join(f"{0.1 * k:.1f},{0.5 * (k // 50 % 2)},"
                                             f"{0.01 * k:.2f}\n" for k in range(300)))
    shown = runner.invoke(app, ["inspect", str(log), "--profile", str(profile_path)])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout, shown.stdout


def test_a_speed_is_drafted_in_metres_per_second_and_a_turn_rate_in_radians(tmp_path):
    """A ground speed is no angular rate: the draft's units follow what each name says."""
    from auvdiag_cli.api import draft_profile

    log = tmp_path / "flight.csv"
    rows = ["time_s,motor_1,yawspeed,groundspeed"]
    rows += [f"{0.1 * k:.1f},{0.2 + 0.1 * (k // 20 % 3)},{0.01 * (k % 7)},{12 + 0.1 * (k % 9)}"
             for k in range(400)]
    log.write_text("\n".join(rows) + "\n")
    text = draft_profile(log)
    units = {sensor["name"]: sensor["unit"] for sensor in tomllib.loads(text)["sensors"]}
    assert units.get("yawspeed") == "rad/s" and units.get("groundspeed") == "m/s", text


def _json_mcap(path: Path, described: bool = True, statistics: bool = True) -> Path:
    """A JSON-encoded MCAP as Foxglove's tools write it (a JSON Schema per channel; or an
    empty one), whose keys hold a dash, a space and a quote, and one of whose values is
    now and then null."""
    import json

    from mcap.writer import Writer

    schema = {"type": "object", "properties": {
        "motor-1": {"type": "number"}, "rpm 2": {"type": "number"},
        'the "depth"': {"type": "object", "properties": {"value": {"type": "number"}}}}}
    if not described:
        schema = {}
    with path.open("wb") as stream:
        writer = Writer(stream, use_statistics=statistics)
        writer.start(profile="", library="test")
        channel = writer.register_channel("/state", "json", writer.register_schema(
            "Thrusters", "jsonschema", json.dumps(schema).encode()))
        for k in range(400):
            time_ns = 1_700_000_000_000_000_000 + k * 100_000_000
            message = {"motor-1": math.sin(k / 20), "rpm 2": math.cos(k / 30),
                       'the "depth"': {"value": None if k % 50 == 7 else k / 10}}
            writer.add_message(channel, log_time=time_ns, publish_time=time_ns,
                               data=json.dumps(message).encode())
        writer.finish()
    return path


@pytest.mark.parametrize(("described", "statistics"), [(True, True), (False, True),
                                                       (False, False)])
def test_json_keys_that_are_no_plain_names_are_listed_drafted_and_read(tmp_path, described,
                                                                      statistics):
    """`inspect` lists a JSON channel's fields from its schema (or, where that lists none,
    from its first message; with the file's statistics or by a scan), a key that is no
    plain name quoted in brackets; the draft writes them as valid TOML and reads each (a
    null: no reading then, where it stopped the read before)."""
    from adapters import read_log
    from auvdiag_cli.vehicle.profile import load_profile

    log = _json_mcap(tmp_path / "state.mcap", described, statistics)
    shown = runner.invoke(app, ["inspect", str(log)])
    assert shown.exit_code == 0, shown.output
    assert 'fields    ["motor-1"], ["rpm 2"], ["the \\"depth\\""].value' in shown.output
    text = _draft_and_inspect(log, tmp_path / "draft.toml")
    assert 'motor_1 = { topic = "/state", field = "[\\"motor-1\\"]" }' in text
    signals = read_log(log, load_profile(tmp_path / "draft.toml").sources).series
    assert signals["motor_1"].values[20] == pytest.approx(math.sin(1.0))
    assert signals["the_depth_value"].values[-1] == pytest.approx(39.9)
    assert len(signals["the_depth_value"]) == 392 and len(signals["motor_1"]) == 400


def test_a_csv_column_named_with_quotes_is_drafted_as_valid_toml(tmp_path):
    log = tmp_path / "quoted.csv"
    log.write_text('time,pwm1,"depth ""m"""\n' + "".join(
        f"{t / 10},{1500 + round(100 * math.sin(t / 10))},{math.sin(t / 7):.3f}\n"
        for t in range(300)))
    text = _draft_and_inspect(log, tmp_path / "draft.toml")
    assert 'depth_m = { column = "depth \\"m\\"" }' in text
    assert tomllib.loads(text)["sources"]["csv"]["signals"]["depth_m"]["column"] == 'depth "m"'


@pytest.mark.parametrize("fmt", ["bag", "db3", "ros2-mcap"])
def test_the_draft_reads_the_log_once(make_log, monkeypatch, fmt):
    """Fields the log does not fill (a command array's elements past its length, an empty
    sequence's first element) read nothing in the one pass; they cost a pass each before,
    which on a long log is minutes."""
    import auvdiag_cli.jobs.profile_draft as draft

    reads = []

    def counted(*args, **kwargs):
        reads.append(args[0])
        return read_log(*args, **kwargs)

    read_log = draft.read_log
    monkeypatch.setattr(draft, "read_log", counted)
    text = draft.draft_profile(make_log("paper-normal", 11, fmt), "once")
    assert len(reads) == 1
    assert all(f'[[commands]]\nname = "{name}"' in text for name in ("data_0", "data_1"))


@pytest.mark.parametrize(("profile", "fmt", "suffix", "expected"), [
    ("bluerov2", "bag", ".bag", 'operating = { topic = "/mavros/state", field = "armed" }'),
    ("px4-armed", "ulog", ".ulg",
     'operating = { message = "actuator_armed", field = "armed", bits = 1 }'),
])
def test_the_draft_reads_the_armed_flag_of_a_mavros_or_px4_log(tmp_path, profile, fmt, suffix,
                                                               expected):
    from adapters import read_log
    from auvdiag_cli import api
    from auvdiag_cli.vehicle.profile import load_profile, profile_text

    if profile == "px4-armed":            # the Twin-Burger logging PX4's armed state
        text, _ = profile_text()
        path = tmp_path / "px4.toml"
        path.write_text(text.replace("[sources.ulog]\n", "[sources.ulog]\noperating = { message "
                                     '= "actuator_armed", field = "armed", bits = 1 }\n'))
        profile = str(path)
    log = tmp_path / f"dive{suffix}"
    api.simulate("paper-normal", api.load_profile(Path(profile)), log, log_format=fmt)
    draft = tmp_path / "draft.toml"
    result = CliRunner().invoke(app, ["init-profile", str(log), "--output", str(draft)])
    assert result.exit_code == 0, result.output
    assert expected in draft.read_text()
    flag = read_log(log, load_profile(draft).sources).series["operating"]
    assert len(flag) > 100 and set(flag.values.tolist()) == {1.0}
