"""A model of the closed loop that still judges its actuators: the profile's commands are the
controller's set points (they drive the model) and the motor outputs are `[[outputs]]`, read
for the effort check only. CSV flights written here: a quadrotor following roll and pitch set
points, its controller sharing the load unequally among four motors; from 15 s motor 3 is
driven harder."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_errors import ProfileError

pytestmark = pytest.mark.slow    # trains a model

RATE_HZ = 50
SHARES = np.array([1.07, 0.87, 1.13, 0.93])
MOTORS = ("motor_1", "motor_2", "motor_3", "motor_4")
ATTITUDE = '''
[[sensors]]
name = "{axis}"
component = "ahrs"
unit = "rad"
full_scale = 0.5
description = "measured {axis}"
moved_by = ["motor_1", "motor_2", "motor_3", "motor_4"]
'''
MOTOR = '''
[[outputs]]
name = "{name}"
component = "{name}"
kind = "rotor"
description = "rotor {name} (ESC output)"
'''
PROFILE = '''
[vehicle]
name = "quad_set_points"
description = "a quadrotor modelled from its attitude set points"
dt_s = 0.1

[[commands]]
name = "roll_sp"
component = "attitude_controller"
kind = "set_point"

[[commands]]
name = "pitch_sp"
component = "attitude_controller"
kind = "set_point"
{sensors}{motors}
[[effort]]
name = "rotors"
actuators = ["motor_1", "motor_2", "motor_3", "motor_4"]
min_level = 0.33

[matching]
window_samples = 10
decision_window_s = 1.0

[thresholds.mission]
roll = 15.0
pitch = 15.0

[sources.csv]
time = {{ column = "time_us", unit = "us" }}

[sources.csv.signals]
roll_sp = {{ column = "roll_sp" }}
pitch_sp = {{ column = "pitch_sp" }}
roll = {{ column = "roll" }}
pitch = {{ column = "pitch" }}
motor_1 = {{ column = "m1", scale = 1.5259021896696422e-05 }}
motor_2 = {{ column = "m2", scale = 1.5259021896696422e-05 }}
motor_3 = {{ column = "m3", scale = 1.5259021896696422e-05 }}
motor_4 = {{ column = "m4", scale = 1.5259021896696422e-05 }}
'''.format(sensors="".join(ATTITUDE.format(axis=a) for a in ("roll", "pitch")),
           motors="".join(MOTOR.format(name=m) for m in MOTORS))


def write_flight(path: Path, seed: int, weak_from_s: float | None = None,
                 motors: bool = True, seconds: float = 40.0) -> Path:
    """A flight following slowly varying roll and pitch set points (first-order lag, noise);
    the four motors' outputs share the load as SHARES, motor 3 carrying 15 % more from
    ``weak_from_s``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, seconds, 1 / RATE_HZ)
    phase = rng.uniform(0, 2 * np.pi, 2)
    set_points = np.column_stack([0.2 * np.sin(t / 2.5 + phase[0]),
                                  0.15 * np.sin(t / 3.7 + phase[1])])
    attitude = np.zeros_like(set_points)
    for k in range(1, len(t)):       # the attitude loop: a 0.3 s lag behind its set point
        attitude[k] = attitude[k - 1] + (set_points[k - 1] - attitude[k - 1]) / (0.3 * RATE_HZ)
    attitude += rng.normal(0, 0.005, attitude.shape)
    shares = np.tile(SHARES * (1 + rng.normal(0, 0.004, 4)), (len(t), 1))
    if weak_from_s is not None:
        shares[t >= weak_from_s, 2] *= 1.15
    shares /= shares.mean(axis=1, keepdims=True)
    level = 0.6 + 0.05 * np.sin(t / 3.0)
    outputs = level[:, None] * shares * (1 + rng.normal(0, 0.03, (len(t), 4)))
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["time_us", "roll_sp", "pitch_sp", "roll", "pitch",
                         *(("m1", "m2", "m3", "m4") if motors else ())])
        for k, time in enumerate(t):
            writer.writerow([int(5e6 + time * 1e6), *set_points[k].round(5),
                             *attitude[k].round(5),
                             *((int(v * 65535) for v in outputs[k]) if motors else ())])
    return path


def invoke(*arguments: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, list(arguments))
    assert "unexpected" not in result.output and "Traceback" not in result.output
    return result.exit_code, result.output


@pytest.fixture(scope="module")
def flights(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("set_point_flights")
    (folder / "quad.toml").write_text(PROFILE)
    for seed in range(4):
        write_flight(folder / f"normal_{seed}.csv", seed)
    write_flight(folder / "later_normal.csv", 40)
    write_flight(folder / "weak_motor_3.csv", 41, weak_from_s=15.0)
    write_flight(folder / "no_motors.csv", 42, motors=False)
    return folder


@pytest.fixture(scope="module")
def model(flights: Path) -> Path:
    target = flights / "model"
    code, output = invoke("train", *(str(flights / f"normal_{s}.csv") for s in range(4)),
                          "--profile", str(flights / "quad.toml"), "--output", str(target),
                          "--iterations-scale", "0.02", "--hidden", "8",
                          # the effort is judged whichever predictor reads the motion
                          "--predictor", "network", "--predictor", "linear")
    assert code == 0, output
    return target


def test_the_set_points_drive_the_model_and_the_outputs_teach_the_effort(model: Path):
    document = json.loads((model / "model.json").read_text())
    assert document["signals"]["commands"] == ["roll_sp", "pitch_sp"]
    group = document["effort"]["groups"][0]
    assert group["members"] == list(MOTORS) and len(group["logs"]) == 4
    share = np.mean(np.atleast_2d(group["normal"]["share"]), axis=0)
    assert share == pytest.approx(SHARES / SHARES.mean(), abs=0.01)


def test_a_motor_output_driven_harder_is_named_with_its_onset(flights: Path, model: Path):
    code, report = diagnose_json(flights / "weak_motor_3.csv", "--profile",
                                 str(flights / "quad.toml"), "--model", str(model))
    assert code == 1, report
    assert report["component"] == "motor_3"
    actuators = report["actuators"]
    assert actuators["named"] == ["motor_3"]
    assert 13.0 <= actuators["onset_s"] <= 17.0 and actuators["alarm_s"] <= 20.0
    assert "a damaged propeller or a weak motor" in actuators["summary"]


def test_a_normal_flight_is_normal_and_a_log_without_outputs_is_still_judged(
        flights: Path, model: Path):
    code, report = diagnose_json(flights / "later_normal.csv", "--profile",
                                 str(flights / "quad.toml"), "--model", str(model))
    assert code == 0, report
    assert report["actuators"]["judged"] and not report["actuators"]["named"]
    # Without the motor outputs the set-point model still judges the motion; the effort
    # says which outputs it lacks, rather than that the motors worked too little.
    code, report = diagnose_json(flights / "no_motors.csv", "--profile",
                                 str(flights / "quad.toml"), "--model", str(model))
    assert code == 0, report
    assert report["verdict"] == "normal"
    why = report["actuators"]["shares"]["motor_1"]["not_judged"]
    assert why == "not judged (this log has no motor_1, motor_2, motor_3, motor_4)"
    assert any("motor_1 is not in this log: an actuator output only the effort check reads"
               in note for note in report["notes"])


def test_training_on_logs_without_the_outputs_says_so(flights: Path, tmp_path: Path):
    logs = [write_flight(tmp_path / f"bare_{seed}.csv", 60 + seed, motors=False)
            for seed in range(3)]
    code, output = invoke("train", *map(str, logs), "--profile", str(flights / "quad.toml"),
                          "--output", str(tmp_path / "bare"), "--iterations-scale", "0.02",
                          "--hidden", "8", "--predictor", "linear", "--keep-unskilled")
    assert code in (0, 1), output
    effort = json.loads((tmp_path / "bare" / "model.json").read_text())["effort"]
    assert effort["refused"] == ("not judged (no log trained on holds motor_1, motor_2, "
                                 "motor_3, motor_4)")


def test_inspect_says_an_output_is_read_for_the_effort_only(flights: Path):
    code, output = invoke("inspect", str(flights / "normal_0.csv"), "--profile",
                          str(flights / "quad.toml"))
    assert code == 0, output
    assert "read for the effort check only" in output


@pytest.mark.parametrize(("change", "replacement", "message"), [
    ('actuators = ["motor_1", "motor_2", "motor_3", "motor_4"]',
     'actuators = ["roll_sp", "pitch_sp"]', "never set points"),
    ('kind = "rotor"', 'kind = "set_point"', "must be one of thruster"),
    ('name = "motor_4"', 'name = "roll"', "must be unique"),
])
def test_outputs_in_a_profile_are_checked(tmp_path: Path, change: str, replacement: str,
                                          message: str):
    from auvdiag_cli.vehicle.profile import load_profile

    assert change in PROFILE
    path = tmp_path / "p.toml"
    path.write_text(PROFILE.replace(change, replacement, 1))
    with pytest.raises(ProfileError, match=message):
        load_profile(path)
