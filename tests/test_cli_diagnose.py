"""End to end through the command line, on real logs and the shipped, really trained model."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.simulator.truth_files import truth_paths

runner = CliRunner()


def truth(log: Path) -> dict:
    return json.loads(truth_paths(log)[0].read_text())


@pytest.mark.parametrize("seed", [11, 12])
def test_paper_scenario_flow_sensor_found_fast(make_log, seed):
    log = make_log("paper-flow-sensor-covered", seed)
    code, report = diagnose_json(log)
    onset = truth(log)["fault"]["onset_s"]
    assert abs(onset - 115.0) < 0.01
    assert code == 1
    assert report["verdict"] == "fault"
    assert report["component"] == "flow_sensor"
    assert report["candidates"] == ["flow_sensor"]
    assert report["case"] == 2
    assert report["b"] == {"flow": 1, "yaw_rate": 0}
    assert abs(report["onset_s"] - onset) <= 2.0
    # Detection after the fault, and much sooner than the paper's ~15 s.
    assert onset < report["detected_at_s"] < onset + 5.0
    assert report["substitution"]["signal"] == "flow"
    assert report["substitution"]["from_s"] == report["onset_s"]


def test_same_mission_without_fault_is_normal(make_log):
    code, report = diagnose_json(make_log("paper-normal", 11))
    assert code == 0
    assert report["verdict"] == "normal"
    assert report["component"] is None and report["candidates"] == []
    assert report["case"] == 0
    assert report["detected_at_s"] is None and report["onset_s"] is None
    segment = report["segments"][0]
    assert segment["mode"] == "mission" and segment["thresholds"] == {"flow": 15.0,
                                                                      "yaw_rate": 10.0}
    assert segment["max_g"]["flow"] < 15.0 and segment["max_g"]["yaw_rate"] < 10.0


@pytest.mark.parametrize("thruster", ["thruster_0", "thruster_1"])
def test_dead_thruster_is_case_1_and_the_hypotheses_name_it(make_log, thruster):
    """The table's case 1 names both thrusters; replayed from the onset, only the one that
    died explains the log."""
    log = make_log(f"mission-{thruster.replace('_', '-')}-dead", 11)
    code, report = diagnose_json(log)
    assert code == 1
    assert report["case"] == 1
    assert report["component"] == thruster and report["candidates"] == [thruster]
    assert any(n.startswith("the pattern table reads b as thruster_0 or thruster_1; replayed "
                            f"from the onset, {thruster.replace('_', ' ')} dead explains")
               for n in report["notes"])
    assert report["detected_at_s"] > truth(log)["fault"]["onset_s"]


def test_dead_yaw_rate_sensor_is_named(make_log):
    log = make_log("mission-yaw-rate-sensor-dead", 11)
    code, report = diagnose_json(log)
    assert code == 1
    assert report["component"] == "yaw_rate_sensor" and report["case"] == 3
    assert abs(report["onset_s"] - truth(log)["fault"]["onset_s"]) <= 2.0


def test_routine_segments_get_routine_thresholds(make_log):
    code, report = diagnose_json(make_log("routine-and-mission", 11))
    assert code == 0
    names = [(s["name"], s["mode"], s["thresholds"]["flow"]) for s in report["segments"]]
    assert names == [("ZA", "routine", 8.0), ("ZB", "routine", 8.0), ("ZC", "routine", 8.0),
                     ("MISSION", "mission", 15.0)]


def test_json_report_has_the_contract_fields(make_log, tmp_path):
    target = tmp_path / "report.json"
    result = runner.invoke(app, ["diagnose", str(make_log("paper-flow-sensor-covered", 11)),
                                 "--json", str(target)])
    assert result.exit_code == 1
    assert "FAULT: flow sensor" in result.stdout
    report = json.loads(target.read_text())
    for key in ("log", "format", "vehicle", "verdict", "component", "candidates", "case", "b",
                "detected_at_s", "onset_s", "segments", "substitution", "model"):
        assert key in report
    assert report["format"] == "ros2-mcap" and report["vehicle"] == "twin-burger"
    assert report["model"]["name"] == "twin_burger"
    assert len(report["model"]["weights_sha256"]) == 64


def test_terminal_summary_of_normal_log(make_log):
    result = runner.invoke(app, ["diagnose", str(make_log("paper-normal", 11))])
    assert result.exit_code == 0
    assert "NORMAL" in result.stdout


def one_line_error(result) -> str:
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    return lines[0]


def test_missing_path_is_exit_2(tmp_path):
    missing = tmp_path / "nope.bag"
    result = runner.invoke(app, ["diagnose", str(missing)])
    assert result.exit_code == 2
    line = one_line_error(result)
    assert str(missing) in line and "no such file" in line


def test_file_that_is_not_a_log_is_exit_2(tmp_path):
    text = tmp_path / "notes.bag"
    text.write_text("not a bag at all\n")
    result = runner.invoke(app, ["diagnose", str(text)])
    assert result.exit_code == 2
    assert "not a log" in one_line_error(result)


def test_empty_file_is_exit_2(tmp_path):
    empty = tmp_path / "empty.mcap"
    empty.touch()
    result = runner.invoke(app, ["diagnose", str(empty)])
    assert result.exit_code == 2
    assert "empty file" in one_line_error(result)


def test_log_without_needed_topic_is_exit_2(tmp_path, profile):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    path = tmp_path / "only_imu"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/other", "std_msgs/msg/String", typestore=store)
        message = store.types["std_msgs/msg/String"](data="hello")
        writer.write(connection, 1, bytes(store.serialize_cdr(message, "std_msgs/msg/String")))
    result = runner.invoke(app, ["diagnose", str(path)])
    assert result.exit_code == 2
    line = one_line_error(result)
    assert "missing topic" in line and "/flow/velocity" in line and str(path) in line


def test_truncated_log_is_analysed_up_to_the_cut(make_log, tmp_path):
    source = make_log("paper-normal", 11, "bag")
    cut = tmp_path / "cut.bag"
    cut.write_bytes(source.read_bytes()[: source.stat().st_size // 2])
    code, report = diagnose_json(cut)
    assert code == 0
    assert report["duration_s"] < 80.0
    assert any("up to the damage" in note for note in report["notes"])


def test_truncated_to_nothing_useful_is_exit_2(make_log, tmp_path):
    source = make_log("paper-normal", 11, "bag")
    cut = tmp_path / "cut.bag"
    cut.write_bytes(source.read_bytes()[:5000])
    result = runner.invoke(app, ["diagnose", str(cut)])
    assert result.exit_code == 2
    assert str(cut) in one_line_error(result)


def test_wrong_model_for_profile_is_exit_2(make_log, tmp_path):
    profile_text = (Path(__file__).parents[1] / "auvdiag_cli" / "vehicle" / "profiles"
                    / "twin_burger.toml").read_text()
    other = tmp_path / "renamed.toml"
    other.write_text(profile_text.replace('name = "yaw_rate"', 'name = "heave"').replace(
        "yaw_rate = ", "heave = ").replace('heave = "yaw_rate"', 'yaw_rate = "heave"'))
    result = runner.invoke(app, ["diagnose", str(make_log("paper-normal", 11)),
                                 "--profile", str(other)])
    assert result.exit_code == 2
    assert "model" in one_line_error(result) and "heave" in result.stderr


def test_console_script_runs_in_a_fresh_process(make_log):
    log = make_log("paper-flow-sensor-covered", 11)
    completed = subprocess.run([sys.executable, "-m", "auvdiag_cli", "diagnose", str(log)],
                               capture_output=True, text=True, timeout=120, check=False)
    assert completed.returncode == 1, completed.stderr
    assert "flow sensor" in completed.stdout


def test_every_command_has_help():
    for command in ("diagnose", "inspect", "train", "calibrate", "simulate", "derive-table",
                    "scenarios"):
        result = runner.invoke(app, [command, "--help"])
        assert result.exit_code == 0
        assert len(result.stdout.split()) > 10
