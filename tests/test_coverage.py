"""A verdict says how much it looked at: with a model that judges one signal of two and
neither actuator, a dive with a covered flow sensor is NORMAL *on part of the vehicle* in
the terminal, the JSON, the PDF, the audit table, the fleet PDF and the trend."""

import json
import shutil
from pathlib import Path

import pandas as pd
import pypdf
import pytest
from typer.testing import CliRunner

from auvdiag_cli.audit.trend import SignalTrend
from auvdiag_cli.cli import app
from models.store import default_model_dir

runner = CliRunner()
PARTIAL = "1 of 2 signals and 0 of 2 actuators judged"


@pytest.fixture(scope="module")
def half_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped Twin-Burger model that cannot predict the flow and has no command
    relations (so neither thruster's commands are judged)."""
    target = tmp_path_factory.mktemp("half") / "model"
    shutil.copytree(default_model_dir(), target)
    meta = json.loads((target / "model.json").read_text())
    meta["skill"]["signals"]["flow"].update(skill=0.05, judged=False)
    meta["command_relations"] = {"refused": "left out of this copy"}
    (target / "model.json").write_text(json.dumps(meta))
    return target


def test_a_normal_on_part_of_the_vehicle_says_so_everywhere_a_dive_is_reported(
        make_log, half_model: Path, tmp_path: Path):
    log = make_log("paper-flow-sensor-covered", 12)
    text = runner.invoke(app, ["diagnose", str(log), "--model", str(half_model), "--json",
                               str(tmp_path / "d.json"), "--pdf", str(tmp_path / "d.pdf")])
    assert text.exit_code == 0, text.output
    lines = text.stdout.splitlines()
    assert lines[1] == f"verdict: NORMAL on {PARTIAL}"
    assert (f"  coverage: {PARTIAL} (not judged: flow, thruster_0, thruster_1); "
            "start judged") in lines
    segment = next(line for line in lines if line.startswith("  segment"))
    assert "flow" in segment and "(not judged)" in segment.split("flow")[1].split(",")[0]
    coverage = json.loads((tmp_path / "d.json").read_text())["coverage"]
    assert coverage == {"summary": PARTIAL, "complete": False,
                        "signals": {"judged": ["yaw_rate"], "not_judged": ["flow"]},
                        "actuators": {"judged": [],
                                      "not_judged": ["thruster_0", "thruster_1"]},
                        "start_judged": True, "judged_from_s": None}
    first = " ".join(pypdf.PdfReader(tmp_path / "d.pdf").pages[0].extract_text().split())
    assert f"NORMAL on {PARTIAL}" in first and f"Judged: {PARTIAL}" in first
    # The healthy margin is over the judged signal only: the covered flow's g is not one.
    assert "(yaw_rate at" in first and "(flow at" not in first
    # With the whole model, the same report is a bare NORMAL over everything.
    whole = runner.invoke(app, ["diagnose", str(make_log("paper-normal", 12))])
    assert whole.stdout.splitlines()[1] == "verdict: NORMAL: no fault detected"
    assert ("  coverage: 2 of 2 signals and 2 of 2 actuators judged; start judged"
            in whole.stdout.splitlines())


def test_the_fleet_shows_what_was_judged_and_can_fail_on_it(make_log, half_model: Path,
                                                             tmp_path: Path):
    fleet = tmp_path / "fleet" / "auv1"
    fleet.mkdir(parents=True)
    for seed in (12, 13):
        shutil.copytree(make_log("paper-flow-sensor-covered", seed), fleet / f"dive{seed}")
    out = tmp_path / "audit"
    common = ["audit", str(fleet.parent), "--model", str(half_model), "-o", str(out), "-j", "1"]
    result = runner.invoke(app, common)
    assert result.exit_code == 0, result.output
    assert "2 normal (2 judged in part)" in result.stdout
    table = pd.read_csv(out / "audit.csv")
    assert table["signals_judged"].tolist() == ["1/2", "1/2"]
    assert table["actuators_judged"].tolist() == ["0/2", "0/2"]
    assert not table["coverage_complete"].any()
    assert pd.read_parquet(out / "audit.parquet")["coverage_complete"].tolist() == [False,
                                                                                   False]
    assert runner.invoke(app, [*common, "--fail-on", "partial"]).exit_code == 1
    fleet_text = " ".join(" ".join(page.extract_text().split())
                          for page in pypdf.PdfReader(out / "audit.pdf").pages)
    assert "2 normal judged in part" in fleet_text
    assert ("signals: judged in every log 1 of 2 (yaw_rate); never: flow" in fleet_text)
    assert "actuators: judged in every log 0 of 2; never: thruster_0, thruster_1" in fleet_text
    trend = runner.invoke(app, ["trend", str(out)])
    assert "  auv1 (2 logs):" in trend.stdout.splitlines()


def test_a_falling_margin_is_written_with_its_own_sign():
    falling = SignalTrend("auv1", "flow", 6, (0.5, 0.49, 0.48, 0.47, 0.46, 0.45), -15, 1.0,
                          -0.005, False, False, None)
    assert "-0.005 a dive" in falling.describe() and "+-" not in falling.describe()


def test_calibrate_sets_thresholds_for_judged_signals_only_and_says_what_each_column_is(
        make_log, half_model: Path, tmp_path: Path):
    out = tmp_path / "calibrated"
    result = runner.invoke(app, ["calibrate", str(make_log("paper-normal", 12)),
                                 "--model", str(half_model), "-o", str(out), "--faulty",
                                 str(make_log("paper-flow-sensor-covered", 12))])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert any(line.startswith("  per mode, its samples of normal data; per judged signal, "
                               "max g (the largest residual index") for line in lines)
    assert any(line.startswith("    flow: skipped, not judged (the model cannot predict it) "
                               "(skill ") and line.endswith("; the profile's threshold 15 % stays")
               for line in lines), lines
    assert any(line.startswith("    yaw_rate     max g ") for line in lines)
    faulty = next(line for line in lines if line.startswith("  faulty "))
    assert "NORMAL (no component named); the largest g of a judged signal reached" in faulty
    mission = json.loads((out / "model.json").read_text())["thresholds"]["mission"]
    assert mission["flow"] == 15.0 and mission["yaw_rate"] != 10.0


def test_help_lists_every_built_in_profile():
    """--help names each profile shipped in the package (px4_uuv was once left out)."""
    from auvdiag_cli.vehicle.profile import builtin_profiles

    text = " ".join(runner.invoke(app, ["diagnose", "--help"], terminal_width=200)
                    .stdout.replace("│", " ").split())
    assert "px4_uuv" in builtin_profiles()
    for name in builtin_profiles():
        assert name in text, name


def test_a_model_driven_by_set_points_counts_signals_only():
    """Set points drive the model but are no actuators: nothing to count of them."""
    from auvdiag_cli.engine.coverage import coverage_of

    coverage = coverage_of(["roll", "yaw_rate"], ["yaw_rate"], [], None, None, None)
    assert coverage.describe() == "1 of 2 signals judged (not judged: yaw_rate); start not judged"
