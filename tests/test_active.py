"""Routine diagnosis on DMS segments and active diagnosis between thruster candidates."""

import copy

import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.engine.active import DmsRun, decide, moved_components
from auvdiag_cli.simulator.writers import write_log

runner = CliRunner()


def report_of(log, *extra):
    return diagnose_json(log, *extra)[1]


@pytest.mark.parametrize(("thruster", "other"), [("thruster_0", "thruster_1"),
                                                 ("thruster_1", "thruster_0")])
def test_zb_and_zc_in_the_log_name_the_dead_thruster(make_log, thruster, other):
    report = report_of(make_log(f"routine-{thruster.replace('_', '-')}-dead", 51, "bag"))
    assert report["verdict"] == "fault" and report["case"] == 1
    assert report["component"] == thruster and report["candidates"] == [thruster]
    evidence = {e["segment"]: e for e in report["active_diagnosis"]["evidence"]}
    tests_it = "ZB" if thruster == "thruster_0" else "ZC"
    clears = "ZC" if tests_it == "ZB" else "ZB"
    assert evidence[tests_it]["faulty"] and evidence[tests_it]["tested"] == [thruster]
    assert not evidence[clears]["faulty"] and evidence[clears]["tested"] == [other]
    segments = {s["name"]: s for s in report["segments"]}
    assert segments[tests_it]["case"] == 1 and segments[clears]["case"] == 0
    assert segments["ZB"]["thresholds"] == {"flow": 8.0, "yaw_rate": 7.0}


def test_without_zb_zc_the_hypotheses_decide_when_they_can(make_log):
    """Thruster 0 dies at 10 s in ZA while driven at 0.6: only its failure explains the
    rest of the log. Thruster 1 dies while ZA drives it at 0.2 (1/25 of full thrust) and
    the hypotheses cannot part the two: both stay, and ZB or ZC is recommended."""
    report = report_of(make_log("za-thruster-0-dead", 51, "bag"))
    assert report["component"] == "thruster_0"
    assert report["active_diagnosis"]["recommended_dms"] == []
    report = report_of(make_log("za-thruster-1-dead", 51, "bag"))
    assert report["component"] is None
    assert report["candidates"] == ["thruster_0", "thruster_1"]
    assert report["active_diagnosis"]["recommended_dms"] == ["ZB", "ZC"]


def test_a_later_routine_log_given_with_decides(tmp_path, make_log):
    later = tmp_path / "routine.bag"
    result = runner.invoke(app, ["simulate", "zb-zc-thruster-1-dead", "--format", "bag",
                                 "--output", str(later), "--start", "2026-11-22T11:30:00Z"])
    assert result.exit_code == 0, result.output
    report = report_of(make_log("za-thruster-1-dead", 51, "bag"), "--with", str(later))
    assert report["component"] == "thruster_1"
    assert [e["log"] for e in report["active_diagnosis"]["evidence"]][-2:] == [str(later)] * 2


def test_a_log_overlapping_in_time_or_from_another_day_is_ignored(tmp_path, make_log):
    overlapping, other_day = tmp_path / "overlap.bag", tmp_path / "tomorrow.bag"
    for path, start in ((overlapping, "2026-11-22T10:00:10Z"), (other_day,
                                                                "2026-11-23T10:00:00Z")):
        result = runner.invoke(app, ["simulate", "zb-zc-thruster-1-dead", "--format", "bag",
                                     "--output", str(path), "--start", start])
        assert result.exit_code == 0
    report = report_of(make_log("za-thruster-1-dead", 51, "bag"), "--with", str(overlapping),
                       "--with", str(other_day))
    assert report["candidates"] == ["thruster_0", "thruster_1"]
    notes = " ".join(report["notes"])
    assert "overlaps this log in time" in notes and "recorded on 2026-11-23" in notes


def test_dms_segments_are_recognised_from_the_commands(tmp_path, dive_cache, profile):
    dive = copy.deepcopy(dive_cache("routine-and-mission", 51))
    dive.markers = []
    path = tmp_path / "unmarked.mcap"
    write_log(dive, profile, path, "mcap")
    report = report_of(path)
    assert report["segment_source"] == "commands"
    names = [(s["name"], s["mode"]) for s in report["segments"]]
    assert names == [("ZA", "routine"), ("ZB", "routine"), ("ZC", "routine"),
                     ("MISSION", "mission")]
    starts = [round(s["start_s"]) for s in report["segments"]]
    assert starts == [0, 30, 60, 90]
    assert report["verdict"] == "normal"


def test_moved_components_and_conflicting_evidence(profile):
    assert moved_components(profile.dms["ZA"], profile) == ("thruster_0", "thruster_1")
    assert moved_components(profile.dms["ZB"], profile) == ("thruster_0",)
    faulty = {"flow": 1, "yaw_rate": 1}
    runs = [(DmsRun("a", "ZB", 100, 200, faulty), 0), (DmsRun("a", "ZC", 200, 300, faulty), 0)]
    result = decide(["thruster_0", "thruster_1"], 50, runs, profile)
    assert result.conflict and result.candidates == ("thruster_0", "thruster_1")
    healthy_before = [(DmsRun("a", "ZB", 0, 40, {"flow": 0, "yaw_rate": 0}), 0)]
    assert decide(["thruster_0", "thruster_1"], 50, healthy_before, profile).evidence == ()
