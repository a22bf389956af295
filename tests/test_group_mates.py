"""Of two members of one effort group, the one whose shares the controller drives harder is
named, where the replay's hypotheses favour the other. A simulated quadrotor's rotor 2
stopped 3 s before its log ended was named "motor 1 dead" by the hypothesis test (g at 24 %
of its threshold, rotor 2 dead at 6.3 times it), while its shares matched rotor 2 weak
alone (1.00) from the moment it stopped: the replay had never seen a rotor's command pushed
that far, and tells the members apart only as far as its normal logs did."""

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import cast

import numpy as np
from helpers import observed
from quad_effort import PROFILE, STEPS, quad_check, quad_commands, quad_model

from auvdiag_cli.engine.effort_check import ActuatorEffort, EffortCheck
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.isolation import name_by_hypotheses
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.narrowing import narrowed
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.vehicle.profile import load_profile

JUDGING = cast(Judging, SimpleNamespace(profile=PROFILE, model=None))
STOPPED_S = STEPS * PROFILE.dt_s - 3.0


def _rotor_2_stopped() -> EffortCheck:
    """The effort check of a log whose rotor 2 is asked all it has from 3 s before its end
    (its propeller lost), judged against three normal logs."""
    rng = np.random.default_rng(5)
    model = quad_model([quad_commands(rng, np.ones(4)) for _ in range(3)])
    commands = quad_commands(rng, np.ones(4))
    commands[round(STOPPED_S / PROFILE.dt_s):, 1] = 1.0
    check = quad_check(model, commands)
    assert check.named == ("motor_2",) and check.matches[0][0] == "motor_2"
    assert check.matches[0][1] >= 0.95
    return check


def _replay_favours_motor_1() -> HypothesisTest:
    return HypothesisTest((Hypothesis("motor_1", "dead", 0.24, 0.0, "rotor"),
                           Hypothesis("gyro", "biased", 0.95),
                           Hypothesis("motor_2", "weakened", 1.34, 0.25, "rotor"),
                           Hypothesis("motor_2", "dead", 6.3, 0.0, "rotor")))


def _replay_detected(onset_s: float, detected_s: float) -> Finding:
    return Finding(verdict=Verdict.FAULT, b={"climb": 1, "yaw_rate": 1}, onset_s=onset_s,
                   detected_at_s=detected_s)


def test_the_shares_name_the_member_the_replay_mistook_for_its_partner():
    effort = _rotor_2_stopped()
    assert effort.onset_s is not None and effort.alarm_s is not None
    finding = name_by_hypotheses(observed(effort, {}),
                                 _replay_detected(STOPPED_S + 0.2, STOPPED_S + 0.7),
                                 _replay_favours_motor_1(), JUDGING)
    assert finding.component == "motor_2" and finding.candidates == ("motor_2",)
    assert ("named by the effort its group carries (its shares match motor_2 weak alone, "
            "begun by the detection): the hypothesis test favours motor 1 dead but it is another "
            "member of that group (g at 24% of its threshold)") in finding.notes[-1]


def test_the_replay_names_where_the_shares_began_later_or_name_no_one():
    """A change in the shares that began after the replay saw its fault is another event;
    without an effort alarm the hypothesis test names as before."""
    effort = _rotor_2_stopped()
    earlier = name_by_hypotheses(observed(effort, {}), _replay_detected(60.0, 62.0),
                                 _replay_favours_motor_1(), JUDGING)
    alone = name_by_hypotheses(observed(None, {}),
                               _replay_detected(STOPPED_S + 0.2, STOPPED_S + 0.7),
                               _replay_favours_motor_1(), JUDGING)
    for finding in (earlier, alone):
        assert finding.component == "motor_1"
        assert "named by the hypothesis test: motor 1 dead explains the log" in (
            finding.notes[-1])


def _as_rov_pairs(actuator: ActuatorEffort) -> ActuatorEffort:
    """The quad's rotors 1 and 2 as a BlueROV2's vertical pair, 3 and 4 as two of its
    horizontal thrusters."""
    number = int(actuator.name[-1])
    return replace(actuator, group="vertical" if number < 3 else "horizontal",
                   component=("thruster_5", "thruster_6", "thruster_2", "thruster_3")[number - 1])


def test_a_member_of_another_group_is_no_group_mate():
    """A BlueROV2's vertical thruster driven harder does not overrule a horizontal one the
    hypotheses name: the shares compare members of one group only."""
    rov = load_profile(Path("bluerov2"))
    stopped = _rotor_2_stopped()
    vertical = replace(stopped, actuators=tuple(map(_as_rov_pairs, stopped.actuators)),
                       named=("thruster_6",), matches=(("motor_2", 1.0),))
    assert vertical.alone_by(STOPPED_S + 0.2, STOPPED_S + 0.7) == "thruster_6"
    test = HypothesisTest((Hypothesis("thruster_1", "weakened", 0.3, 0.5, "thruster"),
                           Hypothesis("depth_rate_sensor", "dead", 3.0)))
    finding = name_by_hypotheses(
        observed(vertical, {}, "bluerov2"),
        _replay_detected(STOPPED_S + 0.2, STOPPED_S + 0.7), test,
        cast(Judging, SimpleNamespace(profile=rov, model=None)))
    assert finding.component == "thruster_1"


def test_the_pattern_tables_candidates_are_narrowed_by_the_shares_not_the_replay():
    """The table reads both rotors; the replay favours rotor 1 decisively, the shares rotor
    2: the shares decide, where without them the replay does."""
    finding = Finding(verdict=Verdict.FAULT, b={"climb": 1}, onset_s=STOPPED_S + 0.2,
                      detected_at_s=STOPPED_S + 0.7, candidates=("motor_1", "motor_2"),
                      hypotheses=_replay_favours_motor_1())
    by_shares = narrowed(observed(_rotor_2_stopped(), {}), finding, (), JUDGING)
    by_replay = narrowed(observed(None, {}), finding, (), JUDGING)
    assert by_shares.candidates == ("motor_2",)
    assert "its shares match motor_2 weak alone" in by_shares.notes[-1]
    assert by_replay.candidates == ("motor_1",)
