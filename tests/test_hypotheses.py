"""The hypothesis test: every single-component fault replayed from the onset, the one that
explains the log named, with its runner-up and the margin between them."""


import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.engine.diagnosis import diagnose
from auvdiag_cli.vehicle.profile import load_profile
from models.store import load_model

runner = CliRunner()


@pytest.mark.parametrize(("scenario", "component", "kind"), [
    ("mission-thruster-0-dead", "thruster_0", "dead"),
    ("mission-thruster-1-dead", "thruster_1", "dead"),
    ("paper-flow-sensor-covered", "flow_sensor", "dead"),
])
def test_the_best_hypothesis_names_the_failed_part(make_log, scenario, component, kind):
    """On a mission the pattern table cannot tell the thrusters apart (case 1 names both);
    the replays under each thruster's failure can."""
    _, report = diagnose_json(make_log(scenario, 17))
    hypotheses = report["hypotheses"]
    assert hypotheses["best"]["component"] == component
    assert hypotheses["best"]["kind"] == kind and hypotheses["best"]["explains"]
    assert hypotheses["runner_up"]["component"] != component
    assert hypotheses["margin"] > 2.0
    assert hypotheses["table_agrees"] is True
    ranked = [h["peak_g_over_threshold"] for h in hypotheses["ranked"]]
    assert ranked == sorted(ranked) and len(ranked) == 2 * 4 + 2 * 4   # every hypothesis


def test_without_a_pattern_table_the_hypotheses_name_the_part(make_log, profile_without):
    profile = load_profile(profile_without("[[pattern]]", "[dms."))
    result = diagnose(make_log("mission-thruster-1-dead", 17), profile, load_model())
    assert result.verdict == "fault" and result.component == "thruster_1"
    assert any(n.startswith("named by the hypothesis test: thruster 1 dead explains the log")
               for n in result.notes)
    sensor = diagnose(make_log("paper-flow-sensor-covered", 17), profile, load_model())
    assert sensor.component == "flow_sensor" and sensor.substitution is not None


def test_an_anomaly_no_single_fault_explains_is_said_so(tmp_path, profile_without):
    """Two sensors dead at once (the flow sensor covered, and the gyro zeroed from the same
    moment on): neither single-sensor hypothesis explains both residuals."""
    import pandas as pd

    log = tmp_path / "double.csv"
    simulated = runner.invoke(app, ["simulate", "paper-flow-sensor-covered", "--format", "csv",
                                    "--seed", "17", "--output", str(log)])
    assert simulated.exit_code == 0, simulated.output
    table = pd.read_csv(log)
    after = table["time_s"] >= table["time_s"].min() + 115.0
    table.loc[after & table["yaw_rate_rps"].notna(), "yaw_rate_rps"] = 0.0
    table.to_csv(log, index=False)
    profile = load_profile(profile_without("[[pattern]]", "[dms."))
    result = diagnose(log, profile, load_model())
    assert result.verdict == "fault" and result.component is None
    assert result.hypotheses is not None and not result.hypotheses.best.explains
    assert any("no single-component fault explains it" in n for n in result.notes)
