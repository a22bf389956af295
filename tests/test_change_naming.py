"""Naming a part from the change test where the replay cannot weigh what changed: the
signals that changed are all ones the replay does not judge (a quadrotor's climb), so the
hypothesis test, scored by the replay's g, has nothing to go on; the change test's own
evidence names the part, and where it points at a sensor while the effort shares match one
actuator weak alone, begun by the change's alarm, the actuator is named."""

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import cast

from helpers import observed

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.change_suspects import beyond_the_replay
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.effort_naming import ActuatorEffort, signature_matches
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.narrowing import narrowed
from auvdiag_cli.engine.other_alarms import apply_change_alarm
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.vehicle.profile import load_profile

PROFILE = load_profile(Path("arducopter_quad"))
SIGNALS = PROFILE.sensor_names
UNJUDGED = {"roll_rate": "no skill", "pitch_rate": "no skill", "climb": "no skill"}


def _judging(not_judged: dict[str, str]) -> Judging:
    return cast(Judging, SimpleNamespace(profile=PROFILE, sensor_names=SIGNALS,
                                         not_judged=not_judged))


def _change(*flagged: str) -> ChangeCheck:
    return ChangeCheck({}, {}, 30.0, alarm_s=75.6, onset_s=67.0, onset_error_s=8.6,
                       flagged={n: 1.2 for n in flagged}, evidence={n: 0.4 for n in flagged})


def _motor_3_weak(onset_s: float) -> EffortCheck:
    shares = tuple(ActuatorEffort(f"motor_{i + 1}", f"motor_{i + 1}", "rotors", 1.0 + d, 1.0,
                                  0.01, d, 2.0 if i == 2 else 0.5, None)
                   for i, d in enumerate([-0.02, -0.01, 0.06, -0.03]))
    return EffortCheck(shares, 0.01, onset_s + 3.0, onset_s, ("motor_3",), (), "",
                       signature_matches(shares), onset_error_s=2.0)


def test_a_change_only_in_signals_the_replay_does_not_judge_is_beyond_it():
    assert beyond_the_replay(_change("climb"), _judging(UNJUDGED))
    assert beyond_the_replay(_change("roll_rate", "pitch_rate"), _judging(UNJUDGED))
    # One of them judged (the yaw rate): the hypothesis test weighs it.
    assert not beyond_the_replay(_change("roll_rate", "yaw_rate"), _judging(UNJUDGED))
    assert not beyond_the_replay(_change("climb"), _judging({}))


def test_the_sensor_whose_own_signal_alone_changed_is_named_unless_the_shares_say_a_rotor():
    normal = Finding(verdict=Verdict.NORMAL, b={n: 0 for n in SIGNALS})
    judging = _judging(UNJUDGED)
    # A dead barometer: the climb alone changed, the shares as on normal logs.
    named = apply_change_alarm(observed(None, UNJUDGED), normal, _change("climb"), judging)
    assert named.verdict == Verdict.FAULT and named.component == "barometer"
    assert named.onset_s == 67.0 and named.detected_at_s == 75.6
    # The body rates changed and motor 3's shares match its weakness from then: motor 3.
    rates = _change("roll_rate", "pitch_rate")
    named = apply_change_alarm(observed(_motor_3_weak(67.0), UNJUDGED), normal, rates,
                               judging)
    assert named.component == "motor_3"
    assert "not gyro, whose signals changed" in named.notes[-1]
    # Shares that began long after the change are another event: the gyro stays named.
    late = replace(_motor_3_weak(90.0), alarm_s=93.0)
    assert apply_change_alarm(observed(late, UNJUDGED), normal, rates,
                              judging).component == "gyro"


def test_a_change_no_one_part_moves_is_named_by_the_shares_where_they_match_one_rotor():
    """A rotor lost mid-flight moves every signal at once, and no part's signature fits
    them all: where its group's shares match one rotor weak from the change, that rotor is
    named; without them, no part is."""
    normal = Finding(verdict=Verdict.NORMAL, b={n: 0 for n in SIGNALS})
    judging = _judging({})
    everything = replace(_change(*SIGNALS), ways={n: "below" for n in SIGNALS})
    unnamed = apply_change_alarm(observed(None, {}), normal, everything, judging)
    assert unnamed.verdict == Verdict.FAULT and unnamed.component is None
    named = apply_change_alarm(observed(_motor_3_weak(67.0), {}), normal, everything, judging)
    assert named.component == "motor_3" and named.onset_s == 67.0
    assert "where no one part moves what changed" in named.notes[-1]


def _weak_in(group: str, members: tuple[str, ...], weak: int, onset_s: float,
             error_s: float, seen_s: float) -> EffortCheck:
    """A BlueROV2 effort check whose ``group`` shares match member ``weak`` weak alone,
    begun at ``onset_s`` (give or take ``error_s``) and seen at ``seen_s``."""
    rise = 0.2
    shares = tuple(ActuatorEffort(m, f"thruster_{m[-1]}", group,
                                  1.0 + (rise if k == weak else -rise / (len(members) - 1)),
                                  1.0, 0.02, rise if k == weak else -rise / (len(members) - 1),
                                  3.0 if k == weak else 0.2, None)
                   for k, m in enumerate(members))
    return EffortCheck(shares, 0.01, seen_s, onset_s, (shares[weak].component,), (), "",
                       signature_matches(shares), onset_error_s=error_s)


def test_a_pattern_row_of_parts_that_move_the_vehicle_alike_is_narrowed_by_the_shares():
    """A BlueROV2's thruster stopped late in a dive: the change test saw the roll rate
    alone change (its row: thruster 5 or thruster 6), or the yaw rate (the four horizontal
    thrusters or the gyro); the effort their group carries names the stopped one, and where
    its shares saw it before the change test, their times are the verdict's."""
    signals = load_profile(Path("bluerov2")).sensor_names
    judging = cast(Judging, SimpleNamespace(profile=load_profile(Path("bluerov2")),
                                            sensor_names=signals, not_judged={}))
    normal = Finding(verdict=Verdict.NORMAL, b={n: 0 for n in signals})
    vertical = ("motor_5", "motor_6")
    roll = ChangeCheck({}, {}, 30.0, alarm_s=106.0, onset_s=105.8, onset_error_s=2.0,
                       flagged={"roll_rate": 3.6}, evidence={"roll_rate": 2.0})
    unnamed = apply_change_alarm(observed(None, {}, "bluerov2"), normal, roll, judging)
    assert unnamed.component is None and unnamed.candidates == ("thruster_5", "thruster_6")
    sixth = _weak_in("vertical", vertical, 1, 106.0, 2.6, 107.9)
    named = apply_change_alarm(observed(sixth, {}, "bluerov2"), normal, roll, judging)
    assert named.component == "thruster_6" and named.candidates == ("thruster_6",)
    assert (named.onset_s, named.detected_at_s) == (105.8, 106.0)    # the change test first
    assert "its shares match thruster_6 weak alone" in named.notes[-1]
    # Shares that began after the change test's alarm are another event.
    later = _weak_in("vertical", vertical, 1, 112.0, 2.6, 113.9)
    assert apply_change_alarm(observed(later, {}, "bluerov2"), normal, roll,
                              judging).component is None
    yaw = ChangeCheck({}, {}, 30.0, alarm_s=126.1, onset_s=114.7, onset_error_s=11.4,
                      flagged={"yaw_rate": 1.2}, evidence={"yaw_rate": 0.3})
    first = _weak_in("horizontal", ("motor_1", "motor_2", "motor_3", "motor_4"), 0, 114.8,
                     0.6, 116.2)
    named = apply_change_alarm(observed(first, {}, "bluerov2"), normal, yaw, judging)
    assert named.component == "thruster_1"
    assert (named.onset_s, named.detected_at_s) == (114.7, 116.2)    # the shares saw it first
    assert "the shares saw it first, at 116.2 s: the verdict's times" in named.notes[-1]
    # A weak vertical thruster: its shares rose from its onset, the roll rate departed
    # seconds later; the change test saw it a moment before the shares' test did.
    late_roll = replace(roll, alarm_s=102.55, onset_s=102.35)
    fifth = _weak_in("vertical", vertical, 0, 88.85, 2.6, 102.75)
    named = apply_change_alarm(observed(fifth, {}, "bluerov2"), normal, late_roll, judging)
    assert named.component == "thruster_5"
    assert (named.onset_s, named.detected_at_s) == (88.85, 102.55)
    assert "the shares date it from ~88.8 s: the verdict's times" in named.notes[-1]


def test_the_tables_candidates_are_narrowed_by_shares_that_changed_by_the_detection():
    """A change dated from a window's residual may begin before the change the shares date
    closely: shares that began after the onset but by the detection are the same event and
    tell the table's candidates apart; shares that began after the detection do not."""
    judging = cast(Judging, SimpleNamespace(profile=PROFILE, model=None))
    finding = Finding(verdict=Verdict.FAULT, b={"climb": 1}, onset_s=65.0, detected_at_s=70.0,
                      candidates=("motor_1", "motor_2", "motor_3", "motor_4", "gyro"))
    begun = narrowed(observed(_motor_3_weak(68.0), {}), finding, (), judging)
    assert begun.candidates == ("motor_3",)
    assert begun.notes[-1].endswith("its shares match motor_3 weak alone, begun by the "
                                    "detection")
    after = narrowed(observed(_motor_3_weak(75.0), {}), finding, (), judging)
    assert after.candidates == finding.candidates
