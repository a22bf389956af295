"""The other built-in vehicles: a three-thruster surge/yaw/heave AUV and a BlueROV2-style
ArduSub ROV, flown by the simulator from their profiles, logged in their formats, judged by
their shipped models."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from adapters import read_log
from auvdiag_cli.cli import app
from auvdiag_cli.engine.missions import mission_path
from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.truth_files import truth_paths
from auvdiag_cli.simulator.writers import write_log
from auvdiag_cli.vehicle.profile import load_profile
from auvdiag_errors import ProfileError

runner = CliRunner()


def run(*args: str) -> tuple[int, str]:
    result = runner.invoke(app, list(args))
    return result.exit_code, result.output


def write(tmp_path: Path, profile_name: str, scenario: str, fmt: str, seed: int = 5) -> Path:
    profile = load_profile(Path(profile_name))
    path = tmp_path / f"{profile_name}-{scenario}.{fmt}"
    write_log(simulate(get_scenario(scenario, profile), profile, seed), profile, path, fmt)
    return path


@pytest.mark.parametrize("fmt", ["bag", "mcap", "tlog", "bin"])
def test_three_thruster_signals_round_trip(tmp_path, fmt):
    profile = load_profile(Path("three_thruster"))
    dive = simulate(get_scenario("dms-zd", profile), profile, 3)
    path = tmp_path / f"zd.{fmt}"
    write_log(dive, profile, path, fmt)
    signals = read_log(path, profile.sources)
    commands = np.asarray(dive.commands.values)
    np.testing.assert_allclose(signals.series["thruster_2"].values, commands[:, 2],
                               atol=0.0013)   # PWM formats quantise to 1/400
    np.testing.assert_allclose(signals.series["heave"].values,
                               np.asarray(dive.sensors["heave"].values)[:, 0], atol=1e-6)
    assert [m.label for m in signals.markers] == ["ZD"]
    # Both DVL velocities travel in one message on ROS and DataFlash, in two on MAVLink.
    assert len(signals.series["surge"]) == len(dive.sensors["surge"].times_s)


def test_three_thruster_vehicle_keeps_the_mission_depths(tmp_path):
    log = write(tmp_path, "three_thruster", "paper-normal", "mcap")
    truth = pd.read_csv(truth_paths(log)[1])
    # Legs at 1.0 m and 1.5 m: it ends the last one at 1.5 m and never overshoots by 0.2 m.
    assert abs(truth["depth_m"].iloc[-1] - 1.5) < 0.05
    assert truth["depth_m"].max() < 1.7
    plan = json.loads(mission_path(log).read_text())
    assert plan["missions"][0]["depths_m"] == [1.0, 1.5, 1.0, 1.5]


def test_derived_three_thruster_table_equals_its_profile():
    code, output = run("derive-table", "--profile", "three_thruster")
    assert code == 0, output
    assert "matches the profile's table" in output
    # The larger table: thrusters 0/1 together, each sensor alone, and the vertical thruster
    # together with the heave sensor; the DMS columns show ZA-ZC see the heave sensor's
    # failure (the vehicle floats up) but not the idle vertical thruster's.
    assert "thruster_0 or thruster_1" in output
    assert "thruster_2 or heave_sensor" in output
    rows = {line.split()[0]: line.split()[1:] for line in output.splitlines()[1:8]}
    assert rows["thruster_2"] == ["000", "000", "000", "001", "001"]
    assert rows["heave_sensor"] == ["001", "001", "001", "001", "001"]


def test_heave_sensor_is_told_from_the_vertical_thruster_by_the_dms(tmp_path):
    log = write(tmp_path, "three_thruster", "routine-heave-sensor-dead", "mcap")
    code, output = run("diagnose", str(log), "--profile", "three_thruster", "--json", "-", "-q")
    assert code == 1
    report = json.loads(output)
    assert report["component"] == "heave_sensor"
    assert report["case"] == 4


def test_vertical_thruster_seen_only_on_zd_is_named_by_the_hypotheses(tmp_path):
    # Dead from 10 s but idle until ZD: ZA-ZC look healthy, so the onset is at ZD, and the
    # DMS runs cannot part the thruster from a heave sensor failing there. Replayed from the
    # onset, only the dead thruster explains what follows.
    log = write(tmp_path, "three_thruster", "routine-thruster-2-dead", "mcap")
    code, output = run("diagnose", str(log), "--profile", "three_thruster", "--json", "-", "-q")
    assert code == 1
    report = json.loads(output)
    assert report["component"] == "thruster_2"
    assert report["hypotheses"]["runner_up"]["component"] == "heave_sensor"
    assert not report["hypotheses"]["runner_up"]["explains"]
    assert report["active_diagnosis"]["recommended_dms"] == []


def test_derived_twin_burger_table_is_unchanged():
    code, output = run("derive-table")
    assert code == 0, output


def test_bluerov2_signals_round_trip_through_a_tlog(tmp_path):
    profile = load_profile(Path("bluerov2"))
    dive = simulate(get_scenario("dms-m3", profile), profile, 3)
    path = tmp_path / "m3.tlog"
    write_log(dive, profile, path, "tlog")
    signals = read_log(path, profile.sources)
    commands = np.asarray(dive.commands.values)
    np.testing.assert_allclose(signals.series["motor_3"].values, commands[:, 2],
                               atol=0.0013)
    # Heave is the negated VFR_HUD climb; surge and sway are two NAMED_VALUE_FLOATs.
    for name in ("heave", "surge", "sway"):
        np.testing.assert_allclose(signals.series[name].values,
                                   np.asarray(dive.sensors[name].values)[:, 0], atol=1e-6)
    assert [m.label for m in signals.markers] == ["M3"]


def test_vehicle_without_a_shipped_model_says_how_to_get_one(tmp_path):
    source = Path(__file__).parents[1] / "auvdiag_cli" / "vehicle" / "profiles" / "bluerov2.toml"
    custom = tmp_path / "myrov.toml"
    custom.write_text(source.read_text().replace('name = "bluerov2"', 'name = "myrov"'))
    log = write(tmp_path, "bluerov2", "dms-m1", "tlog")
    code, output = run("diagnose", str(log), "--profile", str(custom))
    assert code == 2
    assert "no model is shipped for vehicle 'myrov'" in output
    assert "auvdiag train" in output


def bluerov2_report(tmp_path: Path, scenario: str, seed: int = 301) -> tuple[int, dict]:
    log = write(tmp_path, "bluerov2", scenario, "tlog", seed)
    code, output = run("diagnose", str(log), "--profile", "bluerov2", "--json", "-", "-q")
    return code, json.loads(output)


def test_bluerov2_normal_dive_with_every_dms_is_silent(tmp_path):
    code, report = bluerov2_report(tmp_path, "all-dms-and-mission")
    assert code == 0, report["segments"]
    assert [s["name"] for s in report["segments"]] == ["ZA", "ZV", "M1", "M2", "M3", "M4", "M5",
                                                      "M6", "MISSION"]
    assert report["model"]["thresholds_calibrated"] is True


@pytest.mark.parametrize("motor", [1, 3, 5])
def test_bluerov2_dead_motor_is_named_by_the_motor_tests(tmp_path, motor):
    # Dead from 10 s, during ZA: ZA (or ZV) raises the alarm, the motor tests that follow
    # clear every other motor and, with the model's predictions, the sensors.
    code, report = bluerov2_report(tmp_path, f"routine-thruster-{motor}-dead")
    assert code == 1
    assert report["component"] == f"thruster_{motor}"
    evidence = {e["segment"]: e["faulty"] for e in report["active_diagnosis"]["evidence"]}
    assert evidence[f"M{motor}"] is True
    assert not any(faulty for name, faulty in evidence.items()
                   if name.startswith("M") and name != f"M{motor}")


@pytest.mark.parametrize(("scenario", "component"), [("routine-dvl-sway-dead", "dvl_sway"),
                                                     ("routine-gyro-dead", "gyro"),
                                                     ("mission-dvl-surge-dead", "dvl_surge")])
def test_bluerov2_failed_sensor_is_named(tmp_path, scenario, component):
    code, report = bluerov2_report(tmp_path, scenario)
    assert code == 1
    assert report["component"] == component
    assert report["substitution"]["signal"] == component.replace("dvl_", "").replace(
        "gyro", "yaw_rate")


def test_bluerov2_yaw_alarm_on_a_mission_names_the_gyro_whose_reading_froze(tmp_path):
    # Seed 302: on seed 301 the vehicle, spinning three times faster than on any training
    # dive once its gyro reads 0, also lifts the heave bit (the model predicts far outside
    # what it learnt) and no row of the table fits. Here the table reads the yaw bit as any
    # horizontal thruster or the gyro (case 1); the gyro's readings froze at 0 from the
    # onset while the model has the vehicle turn, which no thruster's fault gives.
    code, report = bluerov2_report(tmp_path, "mission-gyro-dead", seed=302)
    assert code == 1
    assert report["case"] == 1 and report["component"] == "gyro"
    assert report["active_diagnosis"]["candidates_before"] == [
        "thruster_1", "thruster_2", "thruster_3", "thruster_4", "gyro"]
    assert report["active_diagnosis"]["recommended_dms"] == []
    assert any("gyro is the sensor whose every reading froze" in n for n in report["notes"])
    assert report["substitution"]["signal"] == "yaw_rate"


def test_bluerov2_dead_vertical_thruster_on_a_mission_shows_in_the_roll(tmp_path):
    # The controller holds the vehicle level: the remaining vertical thruster cannot hold
    # both depth and level alone, and the roll rate departs; the table reads both vertical
    # thrusters, and the effort they carry tells them apart (the controller drives the
    # dead one to its limit from then), the shares' change begun by the detection.
    code, report = bluerov2_report(tmp_path, "mission-thruster-6-dead")
    assert code == 1
    assert report["b"]["roll_rate"] == 1 and report["case"] in (4, 5)
    assert report["active_diagnosis"]["candidates_before"] == ["thruster_5", "thruster_6"]
    assert report["candidates"] == ["thruster_6"] and report["component"] == "thruster_6"
    assert any(n.endswith("its shares match thruster_6 weak alone, begun by the detection")
               for n in report["notes"])


def test_formats_a_profile_cannot_write_are_refused(tmp_path):
    code, output = run("simulate", "paper-normal", "--profile", "bluerov2", "--format", "bin",
                       "-o", str(tmp_path / "x.bin"))
    assert code == 2
    assert "no [sources.dataflash] table" in output


def test_twin_burger_model_is_refused_for_another_vehicle(tmp_path):
    log = write(tmp_path, "bluerov2", "dms-m1", "tlog")
    code, output = run("diagnose", str(log), "--profile", "bluerov2", "--model",
                       str(Path(__file__).parents[1] / "models" / "twin_burger"))
    assert code == 2
    assert "model" in output and "bluerov2" in output.lower()


@pytest.mark.parametrize(("edit", "message"), [
    ("[simulation.dofs.flip]\ninertia = 1.0\nlinear_drag = 1.0\nquadratic_drag = 1.0\n",
     "simulation.dofs' must name some of surge, sway, heave, yaw, roll, pitch"),
    ('[[simulation.sensors]]\nsensor = "ghost"\nmeasures = "surge"\nrate_hz = 10.0\n'
     'noise = 0.0\nquantum = 0.001\n', "simulation.sensors' must describe the sensors"),
])
def test_simulation_table_errors_name_the_key(tmp_path, edit, message):
    source = Path(__file__).parents[1] / "auvdiag_cli" / "vehicle" / "profiles" / "twin_burger.toml"
    path = tmp_path / "edited.toml"
    path.write_text(source.read_text() + "\n" + edit)
    with pytest.raises(ProfileError, match=message):
        load_profile(path)
