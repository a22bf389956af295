"""The hypothesis test: every single-component fault replayed from the onset, the one that
explains the log named, with its runner-up and the margin between them."""

import numpy as np
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.engine.diagnosis import diagnose
from auvdiag_cli.engine.hypotheses import KEPT_MOVING, still_moving
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
    assert len(ranked) == 2 * 4 + 2 * 4                                 # every hypothesis
    # The replayed ones best first, then those ruled out without a replay (no g).
    replayed = [g for g in ranked if g is not None]
    assert ranked == replayed + [None] * (len(ranked) - len(replayed))
    assert replayed == sorted(replayed)


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


@pytest.mark.parametrize(("scenario", "dead_sensor"), [
    ("mission-thruster-1-dead", None),
    ("paper-flow-sensor-covered", "flow_sensor"),
])
def test_a_sensor_that_keeps_reading_is_neither_dead_nor_stuck(make_log, scenario,
                                                                dead_sensor):
    """A sensor reading one value from the onset on is what "dead" and "stuck" replay: one
    whose signals keep changing as before is ruled out of both, and the report says why;
    the covered flow sensor (reading 0) is not."""
    _, report = diagnose_json(make_log(scenario, 17))
    by_part = {(h["component"], h["kind"]): h for h in report["hypotheses"]["ranked"]}
    for sensor in ("flow_sensor", "yaw_rate_sensor"):
        for kind in ("dead", "stuck"):
            hypothesis = by_part[(sensor, kind)]
            if sensor == dead_sensor:
                assert hypothesis["ruled_out"] is None
                assert hypothesis["peak_g_over_threshold"] is not None
            else:
                assert hypothesis["ruled_out"] == KEPT_MOVING and not hypothesis["explains"]
                assert hypothesis["peak_g_over_threshold"] is None
        assert by_part[(sensor, "biased")]["ruled_out"] is None


def test_still_moving_allows_for_an_onset_dated_early():
    rng = np.random.default_rng(3)
    noise = rng.normal(0, 0.01, 600)
    assert still_moving(noise, 300)
    dead = noise.copy()
    dead[300:] = 0.0
    assert not still_moving(dead, 300)
    assert not still_moving(dead, 290)              # ten of its last readings after it
    quantised = np.round(noise, 1)                  # one value before the onset as well
    assert not still_moving(quantised, 300)
    assert not still_moving(noise, 0)               # nothing before it to compare
