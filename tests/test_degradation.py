"""Beyond assumption 3: a thruster at half power is named, not mistaken for a sensor; a
sensor that explains the log as well as a weak thruster keeps the table's reading."""


import pytest
from helpers import diagnose_json

from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.isolation import _outweighs_the_table
from auvdiag_cli.engine.results import Finding, Verdict


@pytest.mark.parametrize("thruster", ["thruster_0", "thruster_1"])
def test_half_power_thruster_is_named_with_its_fraction(make_log, thruster):
    log = make_log(f"mission-{thruster.replace('_', '-')}-weak", 81, "bag")
    exit_code, report = diagnose_json(log)
    assert exit_code == 1
    assert report["component"] == thruster and report["candidates"] == [thruster]
    assert report["degradation"]["kind"] == "weakened"
    assert report["degradation"]["thrust_fraction"] == 0.5
    assert report["degradation"]["peak_g_over_threshold"] < 1.0
    assert report["substitution"] is None
    assert any("partial failure" in note for note in report["notes"])


@pytest.mark.parametrize(("scenario", "component"), [
    ("paper-flow-sensor-covered", "flow_sensor"),
    ("mission-yaw-rate-sensor-dead", "yaw_rate_sensor")])
def test_dead_sensors_are_not_explained_away(make_log, scenario, component):
    _, report = diagnose_json(make_log(scenario, 81, "bag"))
    assert report["component"] == component and report["degradation"] is None


@pytest.mark.parametrize("onset_s", [77.2, 49.2])    # in a turn; at low speed after one
def test_thruster_dying_in_a_turn_is_not_read_as_the_yaw_sensor(tmp_path, onset_s):
    # The 5 m x 2.5 m clockwise rectangle, seed 2002: the yaw bit rises alone first, which
    # the table reads as the yaw-rate sensor; replaying with the thruster dead explains all.
    from auvdiag_cli.simulator.faults import Fault
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import Scenario, _mission
    from auvdiag_cli.simulator.writers import write_log
    from auvdiag_cli.vehicle.profile import load_profile

    profile = load_profile()
    scenario = Scenario("turn", "thruster 0 dies in a turn", _mission(length_m=5.0, width_m=2.5),
                        Fault("thruster_0", "dead", onset_s))
    log = tmp_path / "turn.mcap"
    write_log(simulate(scenario, profile, 2002), profile, log, "mcap")
    _, report = diagnose_json(log)
    assert report["component"] == "thruster_0" and report["case"] == 1
    assert report["degradation"] is None and report["substitution"] is None
    assert any("reads b as yaw_rate_sensor" in note and "dead from the onset" in note
               for note in report["notes"])


def test_b_that_fits_no_row_is_a_fault_without_a_case(make_log, tmp_path):
    from importlib import resources

    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    row = ('[[pattern]]\ncase = 3\nb = { flow = 0, yaw_rate = 1 }\n'
           'components = ["yaw_rate_sensor"]\n')
    assert row in text
    partial = tmp_path / "partial.toml"
    partial.write_text(text.replace(row, ""))
    code, report = diagnose_json(make_log("mission-yaw-rate-sensor-dead", 81, "bag"),
                                 "--profile", str(partial))
    assert code == 1 and report["verdict"] == "fault"
    assert report["case"] is None
    assert report["b"] == {"flow": 0, "yaw_rate": 1}
    assert any("fits no row of the pattern table" in note for note in report["notes"])
    # No row names it, but its readings froze at 0 from the onset on: the sensor is named.
    assert report["component"] == "yaw_rate_sensor"
    assert any("whose every reading froze" in note for note in report["notes"])


@pytest.mark.parametrize(("sensor_ratio", "thruster_ratio", "overrules"), [
    (0.36, 0.35, False),    # a dead DVL and a weak thruster explain the log alike
    (1.5, 0.35, True),      # the table's sensor does not explain it
    (0.8, 0.3, True),       # the thruster explains it decisively better
])
@pytest.mark.parametrize("sensor_fault", ["dead", "biased"])
def test_a_weak_thruster_overrules_the_tables_sensor_only_when_it_explains_more(
        sensor_ratio, thruster_ratio, overrules, sensor_fault):
    """Only a sensor fault with nothing fitted (dead, stuck) holds the table's reading: a
    bias fitted to the log absorbs a weak thruster's effect on its one signal."""
    weak = Hypothesis("thruster_1", "weakened", thruster_ratio, 0.5, "thruster")
    sensor = Hypothesis("dvl_surge", sensor_fault, sensor_ratio)
    test = HypothesisTest(tuple(sorted((weak, sensor), key=lambda h: h.peak_g_ratio)))
    finding = Finding(verdict=Verdict.FAULT, b={"surge": 1}, component="dvl_surge")
    assert _outweighs_the_table(weak, finding, test) is (overrules or sensor_fault == "biased")
