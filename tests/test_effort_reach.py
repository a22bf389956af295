"""A weak member of a group its mixer cannot drive alone (a vectored ROV's four horizontal
thrusters, mixed from surge, sway and yaw) moves the shares along its mixer's reach: under
way, its own share up and its fore-and-aft partner's down by as much, the other two near
normal. The naming uses that signature, taken from the profile's controller mix and the
log's own commands. So does the change within a log, judged over the steps under way in
the direction the normal logs mostly push (their change bin) in the noise of the thrusters
moving together; the whole log is judged along the plain signature (its own share up, the
others' down alike), as is a group its mixer reaches in every direction."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from auvdiag_cli.engine.effort_check import check_effort
from auvdiag_cli.vehicle.profile import load_profile
from models.effort_model import EffortLog, EffortModel, learn_effort
from models.effort_reach import reach, rises, signature_directions

PROFILE = load_profile(Path("bluerov2"))
STEPS = 1500                      # 150 s at 10 Hz
WEAK_FROM = 600
# The profile's vectored mix over surge, yaw and sway (motors 1-4).
MIX = np.array([[PROFILE.controller.mix[f"motor_{k}"].get(e, 0.0)   # type: ignore[union-attr]
                 for e in ("surge", "yaw", "sway")] for k in range(1, 5)])


def test_the_reach_of_a_vectored_mix_misses_the_direction_all_four_push_alike():
    projection = reach(MIX)
    assert projection is not None
    np.testing.assert_allclose(projection, np.eye(4) - 0.25, atol=1e-12)
    # Thrust, roll, pitch and yaw reach every direction of a quadrotor's four rotors.
    quad = np.array([[-1, -1, 1, 1], [-1, 1, -1, 1], [-1, 1, 1, -1], [-1, -1, -1, -1]], float)
    assert reach(quad) is None
    # Under way (motors 1 and 2 pushing in reverse), thruster 1's signature: its share up,
    # thruster 2's down as much, the other two unmoved.
    forward = np.tile(np.array([-0.3, -0.3, 0.3, 0.3]), (100, 1))
    toward = signature_directions(rises(forward, np.ones(4), projection), np.ones(4),
                                  np.ones(4))
    np.testing.assert_allclose(toward[0], [0.5 ** 0.5, -(0.5 ** 0.5), 0, 0], atol=1e-9)
    np.testing.assert_allclose(toward[3], [0, 0, -(0.5 ** 0.5), 0.5 ** 0.5], atol=1e-9)


def test_the_profile_gives_the_reach_and_the_model_keeps_it():
    groups = {g.name: g for g in PROFILE.effort_groups}
    horizontal = groups["horizontal"].projection
    assert horizontal is not None and horizontal.shape == (4, 4)
    assert groups["vertical"].reach is None        # heave and roll: both directions of two
    assert all(g.reach is None for g in load_profile(Path("arducopter_quad")).effort_groups)
    model = _model(np.random.default_rng(3))
    again = EffortModel.from_json(json.loads(json.dumps(model.to_json())))
    assert again.setups[0].group.reach == model.setups[0].group.reach is not None
    # the tilt balance of a group the mix reaches every way (the vertical pair's roll)
    assert [s.group.balance for s in again.setups] == [s.group.balance for s in model.setups]
    assert any(s.group.balance is not None for s in model.setups)


def _commands(rng: np.random.Generator, kept: float = 1.0) -> np.ndarray:
    """Four horizontal and two vertical thrusters under way (surge 0.3, small yaw and sway
    corrections); from WEAK_FROM thruster 1 gives ``kept`` of its thrust and the controller
    asks again for the same surge, yaw and sway through its mix."""
    t = np.arange(STEPS)
    wrench = np.column_stack([0.3 + 0.02 * np.sin(t / 90.0) + rng.normal(0, 0.01, STEPS),
                              rng.normal(0, 0.03, STEPS), rng.normal(0, 0.03, STEPS)])
    horizontal = wrench @ MIX.T * (1 + rng.normal(0, 0.005, 4))     # this log's own trim
    if kept < 1:
        thrust = np.diag([kept, 1.0, 1.0, 1.0])
        allocation = np.linalg.pinv(MIX)
        again = np.linalg.inv(allocation @ thrust @ MIX)
        horizontal[WEAK_FROM:] = (wrench[WEAK_FROM:] @ again.T) @ MIX.T
    horizontal *= 1 + rng.normal(0, 0.03, horizontal.shape)
    vertical = 0.2 + rng.normal(0, 0.02, (STEPS, 2))
    return np.column_stack([horizontal, vertical])


def _log(commands: np.ndarray, name: str) -> EffortLog:
    return EffortLog(name, commands, np.ones(len(commands), bool), PROFILE.command_names)


def _model(rng: np.random.Generator, groups=PROFILE.effort_groups) -> EffortModel:  # type: ignore[no-untyped-def]
    model, _ = learn_effort(groups, [_log(_commands(rng), f"normal-{i}") for i in range(6)],
                            PROFILE.dt_s)
    assert model is not None and model.thresholds is not None
    return model


PLAIN = tuple(replace(g, reach=None) for g in PROFILE.effort_groups)
# The same vehicle with no mixer in its profile: its groups' signatures are the plain ones.
NO_MIXER = replace(PROFILE, effort_groups=PLAIN)


def _judge(model: EffortModel, commands: np.ndarray, profile=PROFILE):  # type: ignore[no-untyped-def]
    return check_effort(model, profile, commands, np.ones(len(commands), bool),
                        profile.dt_s * np.arange(len(commands)))


@pytest.mark.parametrize("seed", [5, 6])
def test_a_weak_horizontal_thruster_matches_its_signature_through_the_mix(seed):
    rng = np.random.default_rng(seed)
    model = _model(rng)
    plain = _model(np.random.default_rng(seed), PLAIN)
    weak = _commands(rng, kept=0.7)
    check, before = _judge(model, weak), _judge(plain, weak, NO_MIXER)
    # Under way the mix raises thruster 1 and lowers thruster 2 (its fore-and-aft partner)
    # by about as much: the plain signature, the others down alike, matches it only so well.
    shares = {a.name: a.departure for a in check.actuators}
    assert shares["motor_1"] > 0.05 and shares["motor_2"] < -0.05
    assert check.named == ("thruster_1",)
    assert check.matches[0][0] == "motor_1" and check.matches[0][1] > 0.95
    assert before.matches and before.matches[0][1] < 0.9
    assert check.onset_s is not None and abs(check.onset_s - WEAK_FROM * PROFILE.dt_s) < 10
    # Judged along the mixer's signatures, the partner pushed down by the mix is no longer a
    # second suspect the way it is along the plain ones, and the alarm comes no later.
    ratios = {a.name: a.ratio for a in check.actuators}
    plain_ratios = {a.name: a.ratio for a in before.actuators}
    assert ratios["motor_1"] > 1 and ratios["motor_1"] == max(ratios.values())
    assert abs(ratios["motor_2"]) < 1 < abs(plain_ratios["motor_2"])
    assert check.alarm_s is not None and before.alarm_s is not None
    assert check.alarm_s <= before.alarm_s


def test_a_model_read_back_names_along_the_same_signatures():
    rng = np.random.default_rng(8)
    model = _model(rng)
    again = EffortModel.from_json(json.loads(json.dumps(model.to_json())))
    weak = _commands(rng, kept=0.7)
    assert _judge(again, weak).matches == _judge(model, weak).matches
    assert _judge(again, weak).matches[0][1] > 0.95



def _without_change_bins(entry: dict) -> dict:  # type: ignore[type-arg]
    """model.json as written before groups had a change bin."""
    for group in entry["groups"]:
        group.pop("change_bin", None)
        group.pop("change_window_s", None)
        for log in group["logs"]:
            log.pop("change", None)
            log.pop("within_cov", None)
            log.pop("long_cov", None)
    return entry


def test_the_change_bin_is_read_back_and_a_model_without_it_judges_every_steady_step():
    rng = np.random.default_rng(8)
    model = _model(rng)
    setup = model.setups[0]
    assert setup.change_bin is not None and setup.change_window_s >= 2.0
    again = EffortModel.from_json(json.loads(json.dumps(model.to_json())))
    assert again.setups[0].change_bin == setup.change_bin
    weak = _commands(rng, kept=0.7)
    assert ([a.ratio for a in _judge(again, weak).actuators]
            == [a.ratio for a in _judge(model, weak).actuators])
    older = EffortModel.from_json(_without_change_bins(json.loads(json.dumps(
        model.to_json()))))
    assert older.setups[0].change_bin is None and older.change_fits[0] is None
    # The same weakness, judged over every steady step along the plain signatures.
    check = _judge(older, weak)
    plain = {a.name: a.ratio for a in check.actuators}
    assert plain["motor_1"] == max(plain.values()) > 1 and check.named[0] == "thruster_1"
