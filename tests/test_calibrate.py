"""`auvdiag calibrate`: thresholds from normal logs, written into the model's metadata."""

import json
import re
import shutil

import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from models.store import default_model_dir

runner = CliRunner()


@pytest.mark.slow
def test_calibrated_thresholds_hold_on_held_out_logs_and_still_detect(make_log, tmp_path):
    model = tmp_path / "model"
    shutil.copytree(default_model_dir(), model)
    weights = (model / "weights.npz").read_bytes()
    normal = [make_log(name, seed) for name, seed in (
        ("paper-normal", 61), ("paper-normal", 62), ("mission-ccw", 61),
        ("mission-large-cw", 61), ("routine-and-mission", 61), ("routine-and-mission", 62))]
    faulty = make_log("paper-flow-sensor-covered", 61)
    result = runner.invoke(app, ["calibrate", *map(str, normal), "--model", str(model),
                                 "--faulty", str(faulty)])
    assert result.exit_code == 0, result.output
    assert "false alarms on those logs: 0" in result.stdout
    assert f"faulty {faulty}: FAULT (flow_sensor); the largest g of a judged" in result.stdout
    meta = json.loads((model / "model.json").read_text())
    assert (model / "weights.npz").read_bytes() == weights
    calibration = meta["calibration"]
    assert calibration["margin"] == 1.5 and len(calibration["normal_logs"]) == 6
    mission = next(m for m in calibration["modes"] if m["mode"] == "mission")
    for signal in ("flow", "yaw_rate"):
        assert meta["thresholds"]["mission"][signal] == round(1.5 * mission["max_g"][signal], 2)
    assert {m["mode"] for m in calibration["modes"]} == {"mission", "ZA", "ZB", "ZC"}

    def diagnose(log):
        out = runner.invoke(app, ["diagnose", str(log), "--model", str(model), "--json", "-",
                                  "-q"])
        return out.exit_code, json.loads(out.stdout)

    for log in (make_log("paper-normal", 63), make_log("mission-large-ccw", 63),
                make_log("routine-and-mission", 63)):
        code, report = diagnose(log)
        assert (code, report["verdict"]) == (0, "normal"), log
        assert report["segments"][-1]["thresholds"] == meta["thresholds"]["mission"]
    code, report = diagnose(make_log("paper-flow-sensor-covered", 63))
    assert report["component"] == "flow_sensor"
    code, report = diagnose(make_log("mission-thruster-1-dead", 63))
    assert report["case"] == 1
    code, report = diagnose(make_log("mission-yaw-rate-sensor-dead", 63))
    assert report["component"] == "yaw_rate_sensor"


def test_calibrate_to_a_copy_leaves_the_model_alone(make_log, tmp_path):
    model, copy = tmp_path / "model", tmp_path / "copy"
    shutil.copytree(default_model_dir(), model)
    before = (model / "model.json").read_text()
    result = runner.invoke(app, ["calibrate", str(make_log("paper-normal", 61)), "--model",
                                 str(model), "--output", str(copy), "--margin", "2"])
    assert result.exit_code == 0, result.output
    assert (model / "model.json").read_text() == before
    assert json.loads((copy / "model.json").read_text())["calibration"]["margin"] == 2.0
    assert (copy / "weights.npz").read_bytes() == (model / "weights.npz").read_bytes()
    # One log is too few for the margin rule to be trusted, and of one day: the output
    # says both.
    assert "1 calibration log(s): the margin times the largest" in result.output
    assert "every calibration log was recorded on 2026-11-22" in result.output
    # A report of another day's log says its thresholds have seen one day; of that day, not.
    assert json.loads((copy / "model.json").read_text())["calibration"]["days"] == [
        "2026-11-22"]
    later = tmp_path / "later.mcap"
    flown = runner.invoke(app, ["simulate", "paper-normal", "-o", str(later), "--format",
                                "mcap", "--seed", "61", "--start", "2026-11-24T09:00:00Z"])
    assert flown.exit_code == 0, flown.output
    for log, said in ((later, True), (make_log("paper-normal", 62), False)):
        report = runner.invoke(app, ["diagnose", str(log), "--model", str(copy), "-q",
                                     "--json", "-"])
        notes = json.loads(report.stdout)["notes"]
        assert any("set on normal logs of one day (2026-11-22) and this log is of 2026-11-24"
                   in note for note in notes) == said, notes
    bad = runner.invoke(app, ["calibrate", str(make_log("paper-normal", 61)), "--model",
                              str(model), "--margin", "0.5"])
    assert bad.exit_code == 2 and "margin below 1" in bad.stderr


def test_floor_keeps_thresholds_at_or_above_the_profiles(make_log, tmp_path):
    model = tmp_path / "model"
    shutil.copytree(default_model_dir(), model)
    normal = [make_log("routine-and-mission", seed) for seed in (61, 62)]
    result = runner.invoke(app, ["calibrate", *map(str, normal), "--model", str(model),
                                 "--floor-at-profile"])
    assert result.exit_code == 0, result.output
    meta = json.loads((model / "model.json").read_text())
    assert meta["calibration"]["floor_at_profile"] is True
    paper = {"mission": {"flow": 15.0, "yaw_rate": 10.0}, "ZA": {"flow": 8.0, "yaw_rate": 7.0}}
    for mode, floors in paper.items():
        for signal, floor in floors.items():
            assert meta["thresholds"][mode][signal] >= floor
    # Without the floor the same logs give a lower mission threshold (the model is better
    # than the paper's): the floor is what kept it.
    plain = runner.invoke(app, ["calibrate", *map(str, normal), "--model", str(model),
                                "--output", str(tmp_path / "plain")])
    assert plain.exit_code == 0
    lower = json.loads((tmp_path / "plain" / "model.json").read_text())["thresholds"]
    assert lower["mission"]["flow"] < 15.0


def test_one_log_setting_a_threshold_alone_is_named(make_log, tmp_path):
    """A faulty dive slipped in among normal ones sets the flow threshold by itself: the
    calibration says which log, and how far above the next it stands."""
    model = tmp_path / "model"
    shutil.copytree(default_model_dir(), model)
    normal = [make_log(name, 61) for name in ("paper-normal", "mission-ccw", "mission-large-cw")]
    odd = make_log("paper-flow-sensor-covered", 61)
    result = runner.invoke(app, ["calibrate", *map(str, normal), str(odd), "--model",
                                 str(model)])
    assert result.exit_code == 0, result.output
    assert f"warning: mission flow: {odd.name} alone sets the threshold" in result.stdout
    assert re.search(rf"flow +max g [\d.]+ % -> threshold [\d.]+ %  \(set by {odd.name}, "
                     r"[\d.]+x the next log's [\d.]+ %\)", result.stdout), result.stdout
    mode = next(m for m in json.loads((model / "model.json").read_text())["calibration"]["modes"]
                if m["mode"] == "mission")
    flow = mode["set_by"]["flow"]
    assert flow["log"] == odd.name and flow["peak_g"] >= 2 * flow["next_log_peak_g"]


def test_too_little_data_keeps_the_profile_thresholds_unless_they_would_alarm(make_log,
                                                                               tmp_path):
    model = tmp_path / "model"
    shutil.copytree(default_model_dir(), model)
    result = runner.invoke(app, ["calibrate", str(make_log("routine-and-mission", 61)),
                                 "--model", str(model), "--margin", "3"])
    assert result.exit_code == 0, result.output
    meta = json.loads((model / "model.json").read_text())
    for mode in meta["calibration"]["modes"]:
        if mode["mode"] == "mission":
            continue
        assert mode["kept_profile_default"] and mode["samples"] < 300
        for signal, threshold in mode["thresholds"].items():
            profile_threshold = {"flow": 8.0, "yaw_rate": 7.0}[signal]
            assert threshold == max(profile_threshold, round(3 * mode["max_g"][signal], 2))
    raised = [m for m in meta["calibration"]["modes"] if m["mode"] != "mission"
              and any(t > {"flow": 8.0, "yaw_rate": 7.0}[k] for k, t in m["thresholds"].items())]
    assert raised            # margin 3 over a DMS's normal g exceeds some profile threshold
