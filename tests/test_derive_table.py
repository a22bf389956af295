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

    text = (resources.files("auvdiag_cli") / "profiles/twin_burger.toml").read_text()
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(text.replace('components = ["flow_sensor"]',
                                  'components = ["yaw_rate_sensor"]').replace(
        'components = ["yaw_rate_sensor"]\n\n# Diagnosis', 'components = ["flow_sensor"]\n\n'
        '# Diagnosis'))
    result = runner.invoke(app, ["derive-table", "--profile", str(wrong)])
    assert result.exit_code == 1
    assert "DIFFERS from the profile's table" in result.stdout
