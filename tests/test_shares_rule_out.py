"""A weakness the effort shares would have shown and did not is ruled out, and a replay
alarm of thresholds no calibration set that nothing explains is not taken for a fault.
CrazyPAD, a model trained on four normal flights: two other normal flights were "FAULT:
motor_2" (its replay at half thrust fitted the forward speed) with motor 2's share in its
normal band, and two "FAULT: unidentified component"."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from quad_effort import PROFILE, STEPS, quad_check, quad_commands, quad_model
from test_slight_alarm import ALARM, NORMAL, RAISED, _seen

from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.results import Verdict
from auvdiag_cli.engine.shares_rule_out import expected_rise, ruled_out_by_shares
from auvdiag_cli.engine.slight_alarm import UNEXPLAINED, beyond_slight
from auvdiag_cli.vehicle.profile import load_profile

END_S = STEPS * PROFILE.dt_s


def _normal_check(weak_rotor_2: float = 1.0):
    """A quad log judged against three normal ones; rotor 2 needing its command raised by
    ``weak_rotor_2`` over the whole log (a weakness its controller makes up for)."""
    rng = np.random.default_rng(11)
    model = quad_model([quad_commands(rng, np.ones(4)) for _ in range(3)])
    return quad_check(model, quad_commands(rng, np.array([1.0, weak_rotor_2, 1.0, 1.0])))


def test_the_rise_a_weakness_asks_of_one_rotor_among_four():
    assert expected_rise(0.5, 4) == pytest.approx((2 ** 0.5 - 1) * 3 / (2 ** 0.5 + 3))
    assert expected_rise(0.75, 4) < expected_rise(0.5, 4) < expected_rise(0.25, 4)
    assert expected_rise(0.0, 4) == expected_rise(0.25, 4)      # dead: at least a quarter's
    assert expected_rise(1.0, 4) == 0.0


def test_which_groups_their_controller_drives_member_by_member():
    # A quadrotor's mix (arducopter_quad) and four rotors without one (crazyflie) drive
    # each rotor alone, and so does the simulated BlueROV2's mix its two vertical thrusters
    # (heave and roll); its four horizontal ones (surge, sway, yaw), and a vectored ROV's
    # thrusters where the profile gives no mix, are not.
    alone = {name: {g.name: g.driven_alone for g in load_profile(Path(name)).effort_groups}
             for name in ("arducopter_quad", "crazyflie", "bluerov2", "bluerov2_heavy")}
    assert alone == {"arducopter_quad": {"rotors": True}, "crazyflie": {"rotors": True},
                     "bluerov2": {"horizontal": False, "vertical": True},
                     "bluerov2_heavy": {"horizontal": False, "vertical": False}}


def test_a_weakness_the_normal_shares_deny_is_ruled_out_from_early_on():
    check = _normal_check()
    assert check.alarm_s is None and all(a.driven_alone for a in check.actuators)
    why = ruled_out_by_shares(check, "motor_2", 0.5, 10.0, "motor 2 weakened to 50% thrust")
    assert why is not None and why.startswith("its share of the effort departed ")
    assert "where motor 2 weakened to 50% thrust would have carried about 2" in why
    # From 3 s before the end the shares barely move: nothing is ruled out.
    assert ruled_out_by_shares(check, "motor_2", 0.5, END_S - 3.0, "") is None
    # Nor what the group does not hold, nor without an effort check.
    assert ruled_out_by_shares(check, "gyro", 0.5, 10.0, "") is None
    assert ruled_out_by_shares(None, "motor_2", 0.5, 10.0, "") is None


def test_a_rotor_driven_harder_is_not_ruled_out():
    check = _normal_check(weak_rotor_2=2 ** 0.5)       # at half its thrust throughout
    rotor_2 = next(a for a in check.actuators if a.component == "motor_2")
    assert rotor_2.driven_harder
    assert ruled_out_by_shares(check, "motor_2", 0.5, 10.0, "") is None


def test_a_group_driven_otherwise_rules_nothing_out():
    check = _normal_check()
    ruled = ruled_out_by_shares(
        replace(check, actuators=tuple(replace(a, driven_alone=False)
                                       for a in check.actuators)),
        "motor_2", 0.5, 10.0, "")
    assert ruled is None


UNEXPLAINED_TEST = HypothesisTest((Hypothesis("thruster_5", "weakened", 1.17, 0.25, "thruster"),
                                   Hypothesis("dvl", "biased", 1.47)))


def test_an_unexplained_alarm_of_uncalibrated_thresholds_is_undetermined_however_far():
    unnamed = replace(ALARM, candidates=(), hypotheses=UNEXPLAINED_TEST)
    judged = beyond_slight(unnamed, NORMAL, _seen(2.65), RAISED)
    assert judged.verdict is Verdict.UNDETERMINED and judged.undetermined_because == UNEXPLAINED
    assert ("(it named no single component) is not taken for a fault: no single-component "
            "fault explains it, the replay's heave reached 2.65 x its threshold") in (
                judged.notes[-1])
    # Explained, calibrated, or crossing a threshold the profile set: the fault stands.
    explained = replace(unnamed, hypotheses=HypothesisTest(
        (replace(UNEXPLAINED_TEST.ranked[0], peak_g_ratio=0.85),)))
    assert beyond_slight(explained, NORMAL, _seen(2.65), RAISED) == explained
    assert beyond_slight(unnamed, NORMAL, _seen(2.65, calibrated=True), RAISED) == unnamed
    assert beyond_slight(unnamed, NORMAL, _seen(2.65), frozenset()) == unnamed


def test_an_alarm_only_a_fitted_reading_explains_is_undetermined_too():
    """A sensor's offset fitted to the log after the onset fits a model's own error as well
    as a fault: on uncalibrated thresholds it decides nothing; a dead or stuck reading, or
    a weakness, that explains it does."""
    def named(*explaining: Hypothesis):
        return replace(ALARM, component=explaining[0].component, candidates=(
            explaining[0].component,), hypotheses=HypothesisTest(explaining))

    biased = named(Hypothesis("dvl", "biased", 0.92), Hypothesis("dvl", "drifting", 0.97))
    judged = beyond_slight(biased, NORMAL, _seen(2.65), RAISED)
    assert judged.verdict is Verdict.UNDETERMINED and judged.undetermined_because == UNEXPLAINED
    assert ("(it named dvl) is not taken for a fault: only a reading fitted to the log after "
            "the onset explains it (dvl biased)") in judged.notes[-1]
    for real in (Hypothesis("dvl", "dead", 0.5),
                 Hypothesis("thruster_5", "weakened", 0.6, 0.5, "thruster")):
        kept = named(real, Hypothesis("dvl", "biased", 0.92))
        assert beyond_slight(kept, NORMAL, _seen(2.65), RAISED) == kept


def test_the_ranking_keeps_a_weakness_ruled_out_without_its_g():
    from auvdiag_cli.engine.hypotheses import _unless_the_shares_rule_out

    check = _normal_check()
    weak = Hypothesis("motor_2", "weakened", 0.85, 0.5, "rotor")
    ruled = _unless_the_shares_rule_out(weak, check, 10.0)
    assert ruled.ruled_out is not None and not ruled.explains
    assert ruled.peak_g_ratio == float("inf")
    assert _unless_the_shares_rule_out(weak, None, 10.0) == weak
    sensor = Hypothesis("gyro", "biased", 0.9)
    assert _unless_the_shares_rule_out(sensor, check, 10.0) == sensor
