"""The simulated vehicle obeys the conventions and physics the diagnosis relies on."""

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.simulator.faults import Fault
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.vehicle import Vehicle
from auvdiag_cli.vehicle.profile import load_profile


def settle(commands, seconds=20.0, gains=(1.0, 1.0)):
    spec = load_profile().simulation
    assert spec is not None
    vehicle = Vehicle(spec)
    vehicle.thruster_gain = list(gains)
    for _ in range(int(seconds / 0.01)):
        vehicle.step(commands, 0.01)
    return vehicle


def test_thruster_0_alone_turns_to_starboard():
    assert settle((0.6, 0.0)).velocity["yaw"] > 0.05
    assert settle((0.0, 0.6)).velocity["yaw"] < -0.05


def test_forward_speed_is_plausible_and_reverse_is_weaker():
    full = settle((1.0, 1.0)).velocity["surge"]
    assert 0.4 < full < 0.6
    assert -settle((-1.0, -1.0)).velocity["surge"] < full


def test_dead_thruster_produces_no_thrust():
    assert settle((0.6, 0.6), gains=(0.0, 1.0)).thrust_n[0] == 0.0


def test_fault_changes_readings_only_after_onset():
    fault = Fault("flow_sensor", "covered", 10.0)
    assert fault.sensor_reading("flow_sensor", 0.3, 9.99) == 0.3
    assert fault.sensor_reading("flow_sensor", 0.3, 10.0) == 0.0
    assert fault.sensor_reading("yaw_rate_sensor", 0.3, 20.0) == 0.3
    with pytest.raises(ValueError, match="unknown fault"):
        Fault("flow_sensor", "exploded", 1.0).check(load_profile())
    with pytest.raises(ValueError, match="unknown fault"):
        Fault("heave_sensor", "dead", 1.0).check(load_profile())


def test_dms_zb_moves_only_thruster_0(dive_cache):
    commands = np.asarray(dive_cache("dms-zb", 11).commands.values)
    assert np.abs(commands[:, 0]).max() > 0.5
    assert np.abs(commands[:, 1]).max() == 0.0


def test_flow_sensor_fault_changes_what_the_controller_does(dive_cache):
    normal, faulty = dive_cache("paper-normal", 11), dive_cache("paper-flow-sensor-covered", 11)
    flow = faulty.sensors["flow"]
    after = np.asarray(flow.times_s) > 115.1
    assert np.all(np.asarray(flow.values)[after] == 0.0)
    # The speed loop, told the vehicle is still, pushes harder than on the healthy run.
    steps = slice(1170, 1200)
    assert (np.asarray(faulty.commands.values)[steps].sum()
            > np.asarray(normal.commands.values)[steps].sum() + 1.0)


def test_paper_mission_ends_a_right_turn_just_before_the_fault(dive_cache):
    truth = dive_cache("paper-normal", 11).truth.set_index("t_s")
    # Heading is about 270 degrees (third right turn done) and the vehicle is nearly still.
    assert abs(truth.loc[115.0, "heading_rad"] - 1.5 * np.pi) < 0.2
    assert truth.loc[115.0, "surge_mps"] < 0.05
    assert truth.loc[110.0, "yaw_rate_rps"] > 0.1


def test_a_thruster_last_works_before_the_vehicle_settles(dive_cache):
    dive = dive_cache("paper-normal", 11)
    truth = dive.truth.set_index("t_s")
    for actuator in range(2):
        thrust = truth[f"thrust_{actuator}_n"].abs()
        start = dive.last_works_s(actuator, 3.0)
        # the last 3 s at its mean thrust or more, and none later
        assert thrust.loc[start:start + 3.0].mean() >= 0.95 * thrust.mean()
        later = thrust.loc[start + 0.5:]
        assert later.rolling(30).mean().max() < thrust.mean()
        assert start < dive.duration_s - 3.0


def test_unknown_scenario_lists_the_known_ones():
    with pytest.raises(KeyError, match="paper-flow-sensor-covered"):
        get_scenario("nonsense", load_profile())


def test_simulate_command_writes_log_and_truth(tmp_path):
    runner = CliRunner()
    out = tmp_path / "dive.bag"
    result = runner.invoke(app, ["simulate", "mission-thruster-1-dead", "--format", "bag",
                                 "--output", str(out), "--seed", "3", "--fault-at", "40"])
    assert result.exit_code == 0, result.output
    assert out.read_bytes().startswith(b"#ROSBAG V2.0")
    truth = json.loads((tmp_path / "dive.truth.json").read_text())
    assert truth["fault"]["component"] == "thruster_1"
    assert truth["fault"]["onset_s"] == pytest.approx(40.0, abs=0.01)
    series = pd.read_csv(tmp_path / "dive.truth.csv")
    assert {"t_s", "surge_mps", "yaw_rate_rps", "x_m", "y_m"} <= set(series.columns)
    again = runner.invoke(app, ["simulate", "paper-normal", "--output", str(out)])
    assert again.exit_code == 2 and "exists already" in again.stderr
    bad = runner.invoke(app, ["simulate", "paper-normal", "--output", str(tmp_path / "x"),
                              "--format", "zip"])
    assert bad.exit_code == 2 and "unknown --format" in bad.stderr
    unflown = runner.invoke(app, ["simulate", "paper-normal", "--profile", "px4_uuv",
                                  "--format", "ulog", "--output", str(tmp_path / "p.ulg")])
    assert unflown.exit_code == 2 and unflown.stderr.strip() == (
        "auvdiag: error: profile 'px4_uuv' has no [simulation] table: nothing describes how "
        "to fly it")
    unlogged = runner.invoke(app, ["simulate", "paper-normal", "--profile", "three_thruster",
                                   "--format", "ulog", "--output", str(tmp_path / "h.ulg")])
    assert unlogged.exit_code == 2 and unlogged.stderr.strip() == (
        "auvdiag: error: profile 'three-thruster' has no [sources.ulog] table: it does not "
        "say how the vehicle logs ulog messages")
    assert not (tmp_path / "h.ulg").exists()


def test_scenarios_command_lists_the_paper_scenario():
    result = CliRunner().invoke(app, ["scenarios"])
    assert result.exit_code == 0 and "paper-flow-sensor-covered" in result.stdout
