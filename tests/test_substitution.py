"""Substituting Control: the model's signal in place of the failed sensor, judged against the
simulator's ground truth."""

import json
from pathlib import Path
from types import SimpleNamespace
from typing import cast

import numpy as np
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.engine import naming
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.substitution import dead_reckon
from auvdiag_cli.simulator.truth_files import truth_paths
from auvdiag_cli.vehicle.profile import load_profile


def test_dead_reckoning_straight_and_turning():
    t = np.arange(0, 10.01, 0.1)
    straight = dead_reckon(t, np.full_like(t, 0.5), np.zeros_like(t))
    assert straight.end == pytest.approx((5.0, 0.0), abs=0.06)
    # A full circle at 0.2π rad/s for 10 s ends where it began, turning to starboard (+y).
    circle = dead_reckon(t, np.full_like(t, 0.5), np.full_like(t, 0.2 * np.pi))
    assert np.hypot(*circle.end) < 0.1
    assert circle.y_m[25] > 0


@pytest.mark.parametrize(("scenario", "signal"), [("paper-flow-sensor-covered", "flow"),
                                                  ("mission-yaw-rate-sensor-dead", "yaw_rate")])
def test_substitution_beats_the_failed_sensor(make_log, scenario, signal):
    log = make_log(scenario, 71, "bag")
    result = CliRunner().invoke(app, ["diagnose", str(log), "--json", "-", "-q",
                                      "--truth", str(truth_paths(log)[1])])
    report = json.loads(result.stdout)
    substitution = report["substitution"]
    assert substitution["signal"] == signal
    assert substitution["from_s"] == report["onset_s"]
    assert substitution["truth_error_rms"] < 0.5 * substitution["failed_sensor_error_rms"]
    assert set(substitution["track_end_m"]) == {"substituted", "failed", "truth"}
    if signal == "flow":
        ends = substitution["track_end_error_m"]
        assert ends["substituted"] < 0.2 * ends["failed"]
        # The paper's model error, and the paper's outcome: the path is finished.
        assert substitution["truth_error_rms"] <= 0.0175
    loop = substitution["closed_loop"]
    assert loop["from_s"] == pytest.approx(report["onset_s"], abs=0.1)
    assert loop["reached_last_waypoint"] and loop["finished_s"] > loop["from_s"]
    assert loop["miss_m"] < 0.5 and loop["last_waypoint_m"] == [0.0, 0.0]


def test_no_truth_no_truth_figures(make_log, tmp_path):
    """Truth beside the log is not looked for: only a caller's --truth lays it against."""
    import shutil

    log = tmp_path / "alone.bag"
    shutil.copy(make_log("paper-flow-sensor-covered", 71, "bag"), log)
    _, report = diagnose_json(make_log("paper-flow-sensor-covered", 71, "bag"))
    assert report["substitution"]["truth_error_rms"] is None
    _, report = diagnose_json(log)
    substitution = report["substitution"]
    assert substitution["truth_error_rms"] is None
    assert set(substitution["track_end_m"]) == {"substituted", "failed"}
    assert substitution["track_end_error_m"] == {}
    assert substitution["closed_loop"] is None


def test_mission_plan_given_explicitly(make_log, tmp_path):
    import shutil

    from auvdiag_cli.engine.missions import mission_path

    source = make_log("paper-flow-sensor-covered", 71, "bag")
    log = tmp_path / "alone.bag"
    shutil.copy(source, log)
    runner = CliRunner()
    _, report = diagnose_json(log, "--mission", str(mission_path(source)))
    assert report["substitution"]["closed_loop"]["reached_last_waypoint"]
    missing = runner.invoke(app, ["diagnose", str(log), "--mission", str(tmp_path / "x.json")])
    assert missing.exit_code == 2 and "no such mission plan" in missing.stderr
    broken = tmp_path / "broken.json"
    broken.write_text('{"missions": [{"waypoints": []}]}')
    bad = runner.invoke(app, ["diagnose", str(log), "--mission", str(broken)])
    assert bad.exit_code == 2 and "unreadable mission plan" in bad.stderr


def test_the_substitute_is_a_signal_the_model_predicts():
    """A failed gyro's substitute: the signal whose bit rose among those the replay judges,
    else the first judged; none where the replay judges none of them (a quadrotor's roll
    and pitch rates, which its model cannot predict, are no stand-in)."""
    profile = load_profile(Path("arducopter_quad"))
    gyro = [s for s in profile.sensors if s.component == "gyro"]
    assert [s.name for s in gyro] == ["roll_rate", "pitch_rate", "yaw_rate"]
    unpredicted = {"roll_rate": "no skill", "pitch_rate": "no skill"}

    def stand_in(raised: str | None, not_judged: dict[str, str]) -> str | None:
        finding = Finding(verdict=Verdict.FAULT, b={s.name: int(s.name == raised)
                                                     for s in profile.sensors})
        seen = cast(Observations, SimpleNamespace(not_judged=not_judged))
        chosen = naming.stand_in(seen, finding, gyro)
        return None if chosen is None else chosen.name

    assert stand_in("yaw_rate", unpredicted) == "yaw_rate"
    assert stand_in("roll_rate", unpredicted) == "yaw_rate"     # its own bit, unjudged
    assert stand_in("pitch_rate", {}) == "pitch_rate"
    assert stand_in(None, {}) == "roll_rate"
    assert stand_in("yaw_rate", {**unpredicted, "yaw_rate": "no skill"}) is None
