"""Faults a controller hides: a weakened thruster the controller makes up for leaves the
motion normal, and shows in how hard the thrusters are driven for that motion."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pypdf
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from auvdiag_cli.vehicle.profile import load_profile
from models.command_relations import (
    WINDOW_S,
    CommandRelations,
    RelationLog,
    fit_relations,
    window_for,
)
from models.store import default_model_dir, load_model

runner = CliRunner()


def _dive(target: Path, profile_name: str, scenario: str, seed: int, fmt: str,
          thrust_fraction: float | None = None) -> Path:
    profile = load_profile(Path(profile_name))
    chosen = get_scenario(scenario, profile, severity=thrust_fraction)
    write_log(simulate(chosen, profile, seed), profile, target, fmt)
    return target


@pytest.mark.slow
def test_a_thruster_at_70_percent_is_found_in_the_commands_and_named(tmp_path):
    """Thruster 0 gives 70 % of its thrust from 60 s: the heading controller drives it
    harder and the motion stays within its thresholds; the commands name it."""
    log = _dive(tmp_path / "weak", "twin_burger", "mission-thruster-0-weak", 7, "ros2-mcap",
                0.7)
    code, report = diagnose_json(log)
    check = report["commands_check"]
    assert code == 1 and report["verdict"] == "fault" and report["component"] == "thruster_0"
    assert not any(report["b"].values())                   # the motion alone says normal
    assert check["named"] == ["thruster_0"] and 60.0 < check["alarm_s"] < 120.0
    assert check["explained"]["thruster_0"] > 3 * check["explained"]["thruster_1"]
    assert 0.15 < check["extra_effort"] < 0.45     # 1/sqrt(0.7) - 1 = 0.20 for thrust ~ c|c|
    assert any(note.startswith("found in the commands, not the motion") for note in
               report["notes"])
    text = runner.invoke(app, ["diagnose", str(log)]).stdout
    assert "commands vs motion: thruster_0 driven harder than the motion needs" in text
    pdf = tmp_path / "report.pdf"
    assert runner.invoke(app, ["diagnose", str(log), "--pdf", str(pdf), "--quiet"]).exit_code == 1
    first = " ".join(pypdf.PdfReader(pdf).pages[0].extract_text().split())
    assert "Commands vs motion: thruster_0 driven harder than the motion needs" in first


@pytest.mark.parametrize("scenario", ["paper-normal", "mission-large-ccw", "mission-sprint-cw"])
def test_normal_missions_keep_every_command_within_its_relation(tmp_path, scenario):
    code, report = diagnose_json(_dive(tmp_path / scenario, "twin_burger", scenario, 23,
                                 "ros2-mcap"))
    check = report["commands_check"]
    assert code == 0 and check["alarm_s"] is None and not check["not_judged"]
    assert all(0.0 < peak < 1.0 for peak in check["peak_over_threshold"].values())


def test_thrusters_the_controller_drives_apart_are_told_apart(tmp_path):
    """The BlueROV2's controller holds its track (the sideways velocity) besides its speed
    and heading, so no two horizontal thrusters always push alike: a weak motor 1 is named
    alone by the commands, not with its diagonal partner (a controller holding speed and
    heading only drives motors 1 and 3 with equal magnitudes). The depth loop drives both
    vertical thrusters alike on normal dives (the level hold only trims them), so the
    commands still take those two as one."""
    relations = load_model(default_model_dir("bluerov2")).relations
    assert relations is not None and relations.groups == ((0,), (1,), (2,), (3,), (4, 5))
    log = _dive(tmp_path / "weak.tlog", "bluerov2", "mission-thruster-1-weak", 7, "tlog")
    code, report = diagnose_json(log, "--profile", "bluerov2")
    assert code == 1 and report["verdict"] == "fault" and report["component"] == "thruster_1"
    assert report["commands_check"]["named"] == ["thruster_1"]
    assert report["candidates"] == ["thruster_1"]


def test_the_relation_reads_back_from_json_and_takes_logs_of_any_length():
    relations = load_model().relations
    assert relations is not None
    again = CommandRelations.from_json(json.loads(json.dumps(relations.to_json())))
    assert np.array_equal(again.weights, relations.weights)
    assert np.array_equal(again.thresholds, relations.thresholds, equal_nan=True)
    assert again.groups == relations.groups == ((0,), (1,))
    for steps in (1, 3, relations.smoothing_steps + 1):
        effort = relations.extra_effort(np.full((steps, 2), 0.5), np.zeros((steps, 2)),
                                        np.ones(steps, bool))
        assert effort.shape == (steps, 2) and np.isnan(effort).all()   # shorter than a window


@pytest.mark.slow
def test_relate_learns_the_relation_for_an_existing_model(make_log, tmp_path):
    model = tmp_path / "model"
    model.mkdir()
    for file in default_model_dir().iterdir():
        (model / file.name).write_bytes(file.read_bytes())
    meta = json.loads((model / "model.json").read_text())
    del meta["command_relations"]
    (model / "model.json").write_text(json.dumps(meta))
    logs = [str(make_log(s, seed)) for s in ("paper-normal", "mission-ccw") for seed in (31, 32)]
    held = str(make_log("mission-large-cw", 33))
    result = runner.invoke(app, ["relate", *logs, "--holdout", held, "--model", str(model)])
    assert result.exit_code == 0, result.output
    # The motion learnt from each thruster's thrust judges the smaller loss here: it fits
    # every log, the held-out one too, and judges each by a fit to the others.
    assert "command relations learned from 5 log(s)" in result.stdout
    assert "  kept: the motion learnt from each actuator's thrust judges" in result.stdout
    learned = load_model(model).relations
    assert learned is not None and np.isfinite(learned.thresholds).all()
    assert Path(held).name in learned.fitted_on.logs
    assert learned.fitted_on.heldout == ("each log judged by a fit to the others",)

    short = str(make_log("dms-zb", 31))         # a DMS only: nothing follows the motion
    refused = runner.invoke(app, ["relate", short, "--model", str(model)])
    assert refused.exit_code == 1 and "too little usable data" in refused.stdout
    assert load_model(model).relations is not None          # what it had is kept


def test_calibration_raises_the_effort_a_calibration_log_needs_and_never_lowers(tmp_path):
    from auvdiag_cli.engine.command_check import CommandCheck
    from auvdiag_cli.jobs.relate import widen_thresholds

    model = load_model()
    entry = model.card.entry("command_relations")
    before, shorter = list(entry["thresholds"]), entry["shorter_windows"][0]["thresholds"]

    def check(*peaks: dict[str, float | None]) -> CommandCheck:
        return CommandCheck(model.command_names, {}, {}, np.empty((0, 2)), peaks, None, None,
                            (), None, None, 30.0)

    quiet = {"thruster_0": 0.1, "thruster_1": None}
    raised = widen_thresholds(model, [check({"thruster_0": 0.9, "thruster_1": 0.5}, quiet),
                                      None, check({"thruster_0": 0.2, "thruster_1": None},
                                                  {"thruster_0": 0.1, "thruster_1": 0.8})],
                              1.5)
    entry = model.card.entry("command_relations")
    after = entry["thresholds"]
    assert raised == {"thruster_0": after[0], "thruster_1 (10 s window)": pytest.approx(
        1.2 * shorter[1], rel=1e-4)} and after[1] == before[1]
    assert after[0] == pytest.approx(1.35 * before[0], rel=1e-4)
    assert entry["shorter_windows"][0]["thresholds"][0] == shorter[0]
    assert model.relations is not None and model.relations.thresholds[0] == after[0]


@pytest.mark.slow
def test_a_manoeuvre_the_relation_has_not_seen_does_not_alarm_for_a_few_seconds(tmp_path):
    """A healthy dive flying the paper's sequences and mission three times over: where one
    mission ends and the next sequence begins, the commands depart from the relation for
    about two seconds, and the 30-s windows ending then go over a threshold. A weakness
    persists; that does not, and the dive is normal."""
    from auvdiag_cli.simulator.scenarios import DMS_ALL, PAPER_MISSION, Scenario

    profile = load_profile(Path("twin_burger"))
    scenario = Scenario("repeated", "three missions", (DMS_ALL + PAPER_MISSION) * 3, None)
    log = tmp_path / "repeated.mcap"
    write_log(simulate(scenario, profile, 100), profile, log, "mcap")
    code, report = diagnose_json(log)
    check = report["commands_check"]
    assert max(check["peak_over_threshold"].values()) > 1.0     # the windows did go over
    assert code == 0 and report["verdict"] == "normal" and check["alarm_s"] is None


def _controlled(seconds: float, drive: float, seed: int) -> RelationLog:
    """A log whose two commands follow its two-signal motion exactly (a controller), driven
    at ``drive`` (rms, of full scale)."""
    rng = np.random.default_rng(seed)
    steps = round(seconds / 0.1)
    motion = np.cumsum(rng.normal(0, 0.05, (steps, 2)), axis=0)
    commands = drive * np.tanh(motion @ np.array([[1.0, 0.3], [-0.4, 1.0]]))
    return RelationLog(f"log{seed}", commands, motion, np.ones(steps, bool))


def test_short_logs_get_windows_that_fit_them_and_say_what_data_is_missing():
    assert window_for([_controlled(3600.0, 0.5, 0)], 0.1) == WINDOW_S
    short = [_controlled(20.0, 0.8, seed) for seed in range(6)]
    assert window_for(short, 0.1) == 10.0            # half a 20 s flight
    assert window_for([_controlled(4.0, 0.8, 0)], 0.1) == 5.0    # never below 5 s
    relations = fit_relations(short[:5], [_controlled(20.0, 0.01, 9)], [1.0, 1.0], 0.1)
    assert relations.window_steps == 100
    assert np.isnan(relations.thresholds).all()       # the held-out flight barely drove them
    assert relations.too_little_heldout(0) == (
        "too little held-out data drove it to set a threshold (0.0 s, needs 10 s: one window)")


def _steered(seconds: float, seed: int) -> RelationLog:
    """A log whose two commands a controller sets from its two-signal motion (a linear law,
    which the relation can learn exactly), the motion a few slow random swings."""
    rng = np.random.default_rng(seed)
    time_s = np.arange(round(seconds / 0.1))[:, None] * 0.1
    motion = np.column_stack([
        0.5 * np.sin(2 * np.pi * time_s / period + rng.uniform(0, 2 * np.pi, 3)).sum(axis=1)
        for period in rng.uniform(8.0, 40.0, (2, 3))])
    commands = 0.3 * motion @ np.array([[1.0, 0.3], [-0.4, 1.0]]) + rng.normal(0, 0.01, (
        len(motion), 2))
    return RelationLog(f"log{seed}", commands, motion, np.ones(len(motion), bool))


def _weakened(log: RelationLog, from_step: int, extra: float) -> RelationLog:
    """``log`` with its first actuator driven ``extra`` harder from ``from_step`` on, as a
    controller drives a thruster that lost thrust."""
    commands = log.commands.copy()
    commands[from_step:, 0] *= 1.0 + extra
    return dataclasses.replace(log, commands=commands)


def test_a_stretch_shorter_than_the_window_is_judged_over_a_shorter_one():
    """A 14 s log is too short for a 30 s window (it must hold half of one); the relations
    also keep a 10 s window, its thresholds set on the held-out logs like the main one's,
    which judges it: a normal one stays within them, a thruster driven twice as hard for
    its last 8 s is found and named, from the shorter window."""
    from auvdiag_cli.engine.command_check import check_commands

    relations = fit_relations([_steered(300.0, seed) for seed in range(4)],
                              [_steered(300.0, seed) for seed in (7, 8)], [1.0, 1.0], 0.1)
    assert [w.steps for w in relations.windows] == [300, 100]
    main, shorter = (w.thresholds for w in relations.windows)
    assert np.isfinite(shorter).all() and (shorter >= main).all()
    again = CommandRelations.from_json(json.loads(json.dumps(relations.to_json())))
    assert [w.steps for w in again.windows] == [300, 100]
    assert np.allclose(again.windows[1].thresholds, shorter)
    older = relations.to_json()
    del older["shorter_windows"]
    assert CommandRelations.from_json(older).windows[1:] == ()   # a model from before

    profile = load_profile(Path("twin_burger"))
    normal = _steered(14.0, 11)
    time_s = np.arange(140) * 0.1
    calm = check_commands(relations, profile, normal.commands, normal.sensors, normal.usable,
                          time_s)
    assert calm.judged and calm.alarm_s is None and not calm.not_judged
    assert [p["thruster_0"] is None for p in calm.peak_by_window] == [True, False]
    weak = _weakened(normal, 60, 1.0)
    found = check_commands(relations, profile, weak.commands, weak.sensors, weak.usable,
                           time_s)
    assert found.named == ("thruster_0",) and found.window_s == 10.0
    assert found.alarm_s is not None and 6.0 <= found.alarm_s < 14.0
    assert "(10 s windows)" in found.describe()
    old_model = dataclasses.replace(relations, shorter=())
    unjudged = check_commands(old_model, profile, weak.commands, weak.sensors, weak.usable,
                              time_s)
    assert unjudged.alarm_s is None and "through one 30 s window" in unjudged.not_judged[
        "thruster_0"]


def test_the_budget_judges_and_sets_each_window_of_the_relations():
    """`calibrate --false-alarm-rate` fits a judge per actuator and window (the shorter
    window's named by its length) and writes each threshold back to its own window."""
    from auvdiag_cli.engine.command_check import CommandCheck
    from auvdiag_cli.jobs.budget import command_judges, with_command_thresholds

    relations = fit_relations([_steered(300.0, seed) for seed in range(4)],
                              [_steered(300.0, seed) for seed in (7, 8)], [1.0, 1.0], 0.1)
    names = ("thruster_0", "thruster_1")
    peaks = ({"thruster_0": 0.5, "thruster_1": None}, {"thruster_0": 0.8, "thruster_1": 0.2})
    check = CommandCheck(names, {}, {}, np.empty((0, 2)), peaks, None, None, (), None, None,
                         30.0)
    assert check.peak_ratio == {"thruster_0": 0.8, "thruster_1": 0.2}
    judges = command_judges(relations, [check, None], names)
    assert [(j.name, j.mode) for j in judges] == [
        ("thruster_0", None), ("thruster_1", None), ("thruster_0", "10 s window"),
        ("thruster_1", "10 s window")]
    shorter = relations.windows[1].thresholds
    assert judges[2].values[0] == pytest.approx(0.8 * shorter[0])
    assert np.isnan(judges[1].values[0]) and np.isnan(judges[0].values[1])
    updated = with_command_thresholds(
        relations, {(None, "thruster_1"): 0.3, ("10 s window", "thruster_0"): 0.9}, names)
    assert updated.thresholds.tolist() == [relations.thresholds[0], 0.3]
    assert updated.windows[1].thresholds.tolist() == [0.9, shorter[1]]


def test_a_model_whose_relations_do_not_fit_its_commands_is_refused_in_one_line(tmp_path):
    from models.store import ModelFileError

    model = tmp_path / "model"
    model.mkdir()
    for file in default_model_dir().iterdir():
        (model / file.name).write_bytes(file.read_bytes())
    meta = json.loads((model / "model.json").read_text())
    meta["command_relations"]["shorter_windows"][0]["thresholds"] = [0.5, 0.5, 0.5]
    (model / "model.json").write_text(json.dumps(meta))
    with pytest.raises(ModelFileError, match=r"model does not load: command relations: a "
                       r"window of 100 steps with 3 thresholds for 2 commands"):
        load_model(model)


def test_held_out_logs_too_short_for_the_main_window_leave_the_shorter_to_judge():
    """A held-out log of 20 s sets no threshold for a 30 s window (it must drive the
    actuator through one whole window) but does for the 10 s one: the actuators are judged
    by that window alone, not called unjudged."""
    from auvdiag_cli.engine.command_check import check_commands

    relations = fit_relations([_steered(300.0, seed) for seed in range(4)],
                              [_steered(20.0, 7)], [1.0, 1.0], 0.1)
    main, shorter = (w.thresholds for w in relations.windows)
    assert np.isnan(main).all() and np.isfinite(shorter).all()
    weak = _weakened(_steered(14.0, 11), 60, 1.0)
    check = check_commands(relations, load_profile(Path("twin_burger")), weak.commands,
                           weak.sensors, weak.usable, np.arange(140) * 0.1)
    assert not check.not_judged and check.named == ("thruster_0",)
