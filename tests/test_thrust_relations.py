"""The commands against the motion judged forward (`models.thrust_relations`): on simulated
BlueROV2 dives written as MAVLink .tlog files, the motion learnt from each thruster's thrust
finds a horizontal thruster kept at 70 % of its thrust, which the commands learnt from the
motion cannot judge on these slow missions, and train keeps that form and says why."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from auvdiag_cli.engine.command_check import _dominant, check_commands
from auvdiag_cli.engine.ingest import ingest
from auvdiag_cli.jobs.relate import learn_relations, relation_log
from auvdiag_cli.reports.training import relation_lines
from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from auvdiag_cli.vehicle.profile import Profile, load_profile
from models.card import Refused
from models.command_relations import CommandRelations, fit_relations
from models.relation_forms import relations_from_json, smallest_loss
from models.relation_windows import RelationLog, RelationsRefused
from models.thrust_relations import ThrustRelations, fit_thrust_relations

TRAINING = ("paper-normal", "mission-ccw", "mission-large-cw")


@pytest.fixture(scope="module")
def bluerov2() -> Profile:
    return load_profile(Path("bluerov2"))


def _dive(folder: Path, profile: Profile, scenario: str, seed: int,
          fraction: float | None = None) -> RelationLog:
    path = folder / f"{scenario}-{seed}-{fraction}.tlog"
    write_log(simulate(get_scenario(scenario, profile, severity=fraction), profile, seed),
              profile, path, "tlog")
    return relation_log(ingest(path, profile), profile)


@pytest.fixture(scope="module")
def learnt(bluerov2: Profile, tmp_path_factory: pytest.TempPathFactory
           ) -> tuple[ThrustRelations, list[RelationLog]]:
    folder = tmp_path_factory.mktemp("bluerov2")
    logs = [_dive(folder, bluerov2, name, 1) for name in TRAINING]
    relations = learn_relations(logs[:2], logs[2:], bluerov2)    # as train holds one out
    assert isinstance(relations, ThrustRelations), relations
    return relations, logs


def _judged(relations: ThrustRelations, profile: Profile, log: RelationLog):
    time_s = profile.dt_s * np.arange(len(log.commands))
    return check_commands(relations, profile, log.commands, log.sensors, log.usable, time_s)


def test_train_keeps_the_form_that_judges_the_smaller_loss_and_says_why(learnt, bluerov2):
    relations, logs = learnt
    loss = smallest_loss(relations)
    other = smallest_loss(fit_relations(logs[:2], logs[2:], [
        bluerov2.full_scales[n] for n in bluerov2.sensor_names], bluerov2.dt_s))
    assert np.median(loss) < np.median(other)
    # The commands learnt from the motion judge no horizontal thruster on these slow
    # missions; the thrust form judges every one, a loss of less than half its thrust.
    assert np.all(other[:4] == 1.0) and np.all(loss[:4] < 0.5)
    lines = relation_lines(relations, bluerov2.command_names, bluerov2.effort_groups)
    assert lines[0].endswith("thrust lost allowed per 45 s window:"), lines
    assert lines[1] == (f"  kept: the motion learnt from each actuator's thrust judges a loss "
                        f"of thrust from {np.median(loss):.0%} (median over the actuators), "
                        f"the commands learnt from the motion from {np.median(other):.0%}")
    # Each log judged by a fit to the others set the thresholds.
    assert relations.fitted_on.logs == tuple(log.name for log in logs)


def test_a_horizontal_thruster_at_70_percent_is_found_and_named(learnt, bluerov2, tmp_path):
    relations, _ = learnt
    check = _judged(relations, bluerov2, _dive(tmp_path, bluerov2, "mission-thruster-4-weak",
                                               301, 0.7))
    assert check.alarm_s is not None and 60.0 < check.alarm_s < 120.0, check.describe()
    assert check.named == ("thruster_4",) and check.measure == "thrust lost"
    assert check.extra_effort is not None and 0.15 < check.extra_effort < 0.6   # 0.3 lost
    assert check.describe().startswith("thruster_4 short of thrust: the motion shows less "
                                       "of it than a healthy one gives (")
    # Weakened from 60 s: dated within the first window over (which began 45 s before its
    # end), the true onset within the error it states.
    assert check.onset_s is not None and check.onset_error_s is not None
    assert check.earliest_s is not None and check.earliest_s <= check.onset_s
    assert abs(check.onset_s - 60.0) <= check.onset_error_s < check.window_s / 2, (
        check.onset_s, check.onset_error_s)
    assert f"it began at ~{check.onset_s:.1f} s" in check.describe()


def test_normal_missions_of_another_seed_raise_no_alarm(learnt, bluerov2, tmp_path):
    relations, _ = learnt
    for name in ("mission-sprint-ccw", "mission-fast-cw"):
        check = _judged(relations, bluerov2, _dive(tmp_path, bluerov2, name, 102))
        assert check.alarm_s is None and check.judged, check.describe()


def test_a_pair_driven_alike_shares_its_effect(learnt, bluerov2):
    """The depth loop drives both vertical thrusters alike: the fit splits their effect on
    the heave evenly, not all to one and none to the other."""
    relations, logs = learnt
    _, features, change = relations.rows(logs[0].commands, logs[0].sensors, logs[0].usable)
    _, parts = relations.parts(features, change, len(bluerov2.commands))
    heave = bluerov2.sensor_names.index("heave")
    five, six = (parts[:, 4, heave] ** 2).sum(), (parts[:, 5, heave] ** 2).sum()
    assert 1 / 3 < five / six < 3


def test_the_relation_reads_back_and_older_models_read_as_the_commands_form(learnt):
    relations, _ = learnt
    entry = json.loads(json.dumps(relations.to_json()))
    again = relations_from_json(entry)
    assert isinstance(again, ThrustRelations) and again.groups == relations.groups
    assert np.allclose(again.weights, relations.weights, atol=1e-8)
    assert np.allclose(again.thresholds, relations.thresholds, atol=1e-6, equal_nan=True)
    assert again.fitted_on == relations.fitted_on
    with pytest.raises(ValueError, match="do not fit 5 signals and 6 commands"):
        relations_from_json({**entry, "weights": entry["weights"][:-1]})
    older = {k: v for k, v in entry.items() if k != "form"}
    with pytest.raises(KeyError):       # no form: the commands' form, which needs a basis
        relations_from_json(older)


def test_one_log_cannot_teach_it_alone(learnt, bluerov2):
    _, logs = learnt
    with pytest.raises(RelationsRefused, match="two logs or more"):
        fit_thrust_relations(logs[:1], [1.0] * 5, bluerov2.dt_s)
    # train splits a single log in time; the commands' form is learnt from its two parts
    kept = learn_relations(logs[:1], [], bluerov2)
    assert not isinstance(kept, Refused)


def test_the_commands_form_is_compared_as_the_thrust_it_makes_up_for(learnt, bluerov2):
    """An extra 20 % of command makes up for 1 - 1/1.2² = 31 % of a thrust that grows with
    the command's square."""
    _, logs = learnt
    commands = fit_relations(logs[:2], logs[2:], [
        bluerov2.full_scales[n] for n in bluerov2.sensor_names], bluerov2.dt_s)
    asked = replace(commands, thresholds=np.full(6, 0.2), skill=np.full(6, 0.9))
    assert np.allclose(smallest_loss(asked), 1 - 1 / 1.2 ** 2)
    unskilled = replace(asked, skill=np.full(6, 0.1))
    assert np.all(smallest_loss(unskilled) == 1.0)
    assert isinstance(asked, CommandRelations)


def test_two_actuators_alike_in_the_log_are_named_as_either():
    groups = tuple((k,) for k in range(6))
    assert _dominant(np.array([0.8, 0.05, 0.1, 0.05, 0.0, 0.0]), groups, 0) == (0,)
    assert _dominant(np.array([0.45, 0.05, 0.43, 0.07, 0.0, 0.0]), groups, 0) == (0, 2)
    assert _dominant(np.array([0.3, 0.25, 0.25, 0.2, 0.0, 0.0]), groups, 0) == ()
    # Two actuators in all: naming both would say nothing (a sensor misreading the motion)
    assert _dominant(np.array([0.5, 0.5]), ((0,), (1,)), 0) == ()


def test_a_sensor_misreading_the_motion_is_kept_among_the_candidates(learnt, bluerov2,
                                                                      tmp_path):
    """A dead gyro leaves the yaw rate alone out of line: the loss the check fits rests on
    that signal, so the gyro stays a candidate; a thruster that died leaves every signal
    it moves short, and its loss rests on none of them alone."""
    relations, _ = learnt
    log = _dive(tmp_path, bluerov2, "mission-gyro-dead", 301)
    gyro = _judged(relations, bluerov2, log)
    assert gyro.alarm_s is not None and (not gyro.named or gyro.rests_on == ("yaw_rate",))
    after = log.usable & (np.arange(len(log.usable)) * bluerov2.dt_s >= 60.0)
    yaw = bluerov2.sensor_names.index("yaw_rate")
    for horizontal in range(4):
        assert relations.rests_on(log.commands, log.sensors, after, (horizontal,)) == (yaw,)
    dead = _judged(relations, bluerov2, _dive(tmp_path, bluerov2, "mission-thruster-2-dead",
                                              301))
    assert dead.named == ("thruster_2",) and dead.rests_on == ()
    assert dead.alarm_s is not None and 60.0 < dead.alarm_s < 70.0


def test_a_peak_below_zero_counts_as_zero_when_thresholds_are_fitted_to_a_budget(learnt,
                                                                                  bluerov2):
    """The check judges one way: a log whose actuator gave more than expected all along
    (its largest loss below zero) came no nearer an alarm than one at zero."""
    from auvdiag_cli.jobs.budget import command_judges

    relations, logs = learnt
    check = _judged(relations, bluerov2, logs[0])
    below = dict(check.peak_by_window[0], motor_5=-0.4)
    judges = command_judges(relations, [replace(check, peak_by_window=(
        below, *check.peak_by_window[1:])), check], bluerov2.command_names)
    main = next(j for j in judges if j.name == "motor_5" and j.mode is None)
    assert main.values[0] == 0.0
    assert main.values[1] == pytest.approx(check.peak_by_window[0]["motor_5"]
                                           * relations.thresholds[4])


def test_neither_form_judges_less_than_the_least_loss_nor_does_a_budget(learnt, bluerov2):
    """A thrust drifts by a few percent with the battery and the water: however quiet the
    held-out logs, neither form's threshold lies below a 10 % loss over its main window
    (the commands' form as the extra command that makes it up, 1/√0.9 - 1), nor below it
    scaled by √3 over the window a third as long; a budget's law keeps the floor too."""
    from auvdiag_cli.jobs.budget import with_command_thresholds
    from models.relation_windows import thresholds_from

    relations, logs = learnt
    commands = fit_relations(logs[:2], logs[2:], [
        bluerov2.full_scales[n] for n in bluerov2.sensor_names], bluerov2.dt_s)
    for form in (relations, commands):
        main, shorter = form.windows[0].steps, form.windows[1].steps
        assert form.as_loss(np.array(form.least_judged(main))) == pytest.approx(0.1)
        assert form.as_loss(np.array(form.least_judged(shorter))) == pytest.approx(
            0.1 * np.sqrt(main / shorter))
        quiet = thresholds_from(np.array([0.0, 0.01, 1.0]), np.full(3, main), main,
                                np.full(3, 0.9), form.least_judged(main))
        assert quiet.tolist() == pytest.approx([form.least_judged(main)] * 2 + [1.5])
    assert commands.least_judged(commands.window_steps) == pytest.approx(1 / np.sqrt(0.9) - 1)
    fitted = with_command_thresholds(relations, {(None, "motor_5"): 0.01,
                                                 (None, "motor_6"): 0.5},
                                     bluerov2.command_names)
    assert fitted.thresholds[4:].tolist() == pytest.approx([0.1, 0.5])
