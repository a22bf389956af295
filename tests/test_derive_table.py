"""The pattern table derived from the model equals the paper's."""

import json

from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()


def test_derived_twin_burger_table_is_the_papers(tmp_path):
    target = tmp_path / "table.json"
    result = runner.invoke(app, ["derive-table", "--json", str(target)])
    assert result.exit_code == 0, result.output
    assert "matches the profile's table" in result.stdout
    data = json.loads(target.read_text())
    table = {row["case"]: (row["b"]["flow"], row["b"]["yaw_rate"], row["components"])
             for row in data["table"]}
    assert table == {0: (0, 0, []), 1: (1, 1, ["thruster_0", "thruster_1"]),
                     2: (1, 0, ["flow_sensor"]), 3: (0, 1, ["yaw_rate_sensor"])}
    signatures = {s["component"]: s["b"] for s in data["signatures"]}
    # ZB moves Thruster 0 only: it sees Thruster 0's loss and not Thruster 1's.
    assert signatures["thruster_0"]["ZB"] == {"flow": 1, "yaw_rate": 1}
    assert signatures["thruster_1"]["ZB"] == {"flow": 0, "yaw_rate": 0}
    assert signatures["thruster_1"]["ZC"] == {"flow": 1, "yaw_rate": 1}


def test_a_profile_with_a_wrong_table_is_flagged(tmp_path):
    from importlib import resources

    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(text.replace('components = ["flow_sensor"]',
                                  'components = ["yaw_rate_sensor"]').replace(
        'components = ["yaw_rate_sensor"]\n\n# Diagnosis', 'components = ["flow_sensor"]\n\n'
        '# Diagnosis'))
    result = runner.invoke(app, ["derive-table", "--profile", str(wrong)])
    assert result.exit_code == 1
    assert "DIFFERS from the profile's table" in result.stdout


def test_without_a_controller_the_mission_is_flown_open_loop(tmp_path, make_log,
                                                             profile_without):
    """No [controller]: the DMSs one after another stand in for the mission, or a normal
    log's own commands (--log); the thrusters then show in yaw first, as nothing steers
    against the loss."""
    profile = profile_without("[controller]", "[matching]")
    for extra in ([], ["--log", str(make_log("paper-normal", 11))]):
        result = runner.invoke(app, ["derive-table", "--profile", str(profile), *extra,
                                     "--json", str(tmp_path / "t.json")])
        assert result.exit_code in (0, 1), result.output
        table = json.loads((tmp_path / "t.json").read_text())
        mission = {s["component"]: s["b"]["mission"] for s in table["signatures"]}
        assert mission["flow_sensor"] == {"flow": 1, "yaw_rate": 0}
        assert mission["yaw_rate_sensor"] == {"flow": 0, "yaw_rate": 1}
        assert mission["thruster_0"]["yaw_rate"] == mission["thruster_1"]["yaw_rate"] == 1
        assert "pattern table derived from the mission signatures" in result.stdout


def test_without_a_controller_or_dms_a_log_is_needed(tmp_path, profile_without):
    text = profile_without("[controller]", "[matching]").read_text()
    dms_free = text[:text.index("[dms.ZA]")] + text[text.index("[sources.ros]"):]
    path = tmp_path / "bare.toml"
    path.write_text(dms_free.replace("[thresholds.ZA]", "[thresholds.XA]")
                    .replace("[thresholds.ZB]", "[thresholds.XB]")
                    .replace("[thresholds.ZC]", "[thresholds.XC]"))
    result = runner.invoke(app, ["derive-table", "--profile", str(path)])
    assert result.exit_code == 2
    assert "describes neither a [controller] nor DMSs: give a normal log" in result.output
