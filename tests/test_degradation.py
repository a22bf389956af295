"""Beyond assumption 3: a thruster at half power is named, not mistaken for a sensor."""

import json

import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app


@pytest.mark.parametrize("thruster", ["thruster_0", "thruster_1"])
def test_half_power_thruster_is_named_with_its_fraction(make_log, thruster):
    log = make_log(f"mission-{thruster.replace('_', '-')}-weak", 81, "bag")
    result = CliRunner().invoke(app, ["diagnose", str(log), "--json", "-", "-q"])
    report = json.loads(result.stdout)
    assert result.exit_code == 1
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
    report = json.loads(CliRunner().invoke(
        app, ["diagnose", str(make_log(scenario, 81, "bag")), "--json", "-", "-q"]).stdout)
    assert report["component"] == component and report["degradation"] is None


def test_b_that_fits_no_row_is_a_fault_without_a_case(make_log, tmp_path):
    from importlib import resources

    text = (resources.files("auvdiag_cli") / "profiles/twin_burger.toml").read_text()
    row = ('[[pattern]]\ncase = 3\nb = { flow = 0, yaw_rate = 1 }\n'
           'components = ["yaw_rate_sensor"]\n')
    assert row in text
    partial = tmp_path / "partial.toml"
    partial.write_text(text.replace(row, ""))
    result = CliRunner().invoke(app, ["diagnose", str(make_log("mission-yaw-rate-sensor-dead",
                                                                81, "bag")),
                                      "--profile", str(partial), "--json", "-", "-q"])
    report = json.loads(result.stdout)
    assert result.exit_code == 1 and report["verdict"] == "fault"
    assert report["case"] is None and report["component"] is None
    assert report["b"] == {"flow": 0, "yaw_rate": 1}
    assert any("fits no row of the pattern table" in note for note in report["notes"])
