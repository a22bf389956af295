"""Naming a part from the change test where the replay cannot weigh what changed: the
signals that changed are all ones the replay does not judge (a quadrotor's climb), so the
hypothesis test, scored by the replay's g, has nothing to go on; the change test's own
evidence names the part, and where it points at a sensor while the effort shares match one
actuator weak alone, begun by the onset, the actuator is named."""

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
