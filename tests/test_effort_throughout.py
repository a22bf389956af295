"""A weakness the effort shares show over a whole log names the part where the motion
departed and no single fault explains it, and tells apart the pattern table's candidates.
A real nano-quadrotor with a cut propeller (CrazyPAD, trained on four normal flights) had
its shares match motor 3 weak (0.99) over the whole flight, while the replay's alarm on its
forward speed, which no hypothesis explained, left the verdict "component not identified":
the effort alone, with the replay quiet, names it."""

from dataclasses import replace
from types import SimpleNamespace
from typing import cast

import numpy as np
from helpers import observed
from quad_effort import PROFILE, STEPS, quad_check, quad_commands, quad_model

from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.isolation import name_by_hypotheses
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.narrowing import narrowed
from auvdiag_cli.engine.results import Finding, Verdict

JUDGING = cast(Judging, SimpleNamespace(profile=PROFILE, model=None))
NONE_EXPLAINS = HypothesisTest((Hypothesis("motor_3", "weakened", 1.27, 0.75, "rotor"),
                                Hypothesis("motor_2", "dead", 2.03, 0.0, "rotor"),
                                Hypothesis("gyro", "biased", 2.5)))


def _normal_model(rng: np.random.Generator):
    return quad_model([quad_commands(rng, np.ones(4)) for _ in range(4)])


def _rotor_3_weak_throughout() -> EffortCheck:
    """Rotor 3 driven 15 % harder over the whole log than on four normal logs."""
    rng = np.random.default_rng(11)
    model = _normal_model(rng)
    check = quad_check(model, quad_commands(rng, np.array([1.0, 1.0, 1.15, 1.0])))
    assert check.named == ("motor_3",) and check.matches[0][0] == "motor_3"
    assert check.onset_error_s is None and check.alarm_s is not None
    return check


def _replay_detected(detected_s: float) -> Finding:
    return Finding(verdict=Verdict.FAULT, b={"climb": 1}, onset_s=detected_s - 0.4,
                   detected_at_s=detected_s)


def test_a_weakness_there_over_the_whole_log_names_the_unexplained_departure():
    effort = _rotor_3_weak_throughout()
    assert effort.throughout() == "motor_3"
    finding = name_by_hypotheses(observed(effort, {}), _replay_detected(3.6), NONE_EXPLAINS,
                                 JUDGING)
    assert finding.component == "motor_3" and finding.candidates == ("motor_3",)
    assert finding.notes[-1].startswith("anomaly on climb: no single-component fault explains")
    assert finding.notes[-1].endswith(
        "named by the effort its group carries (its shares match motor_3 weak alone, over "
        "the whole log)")


def test_a_change_within_the_log_or_no_effort_alarm_names_no_one():
    """Shares that changed late in the log are another event than a departure seen before
    (`weak_alone` dates them); shares within their band say nothing of the departure."""
    rng = np.random.default_rng(5)
    model = _normal_model(rng)
    commands = quad_commands(rng, np.ones(4))
    commands[STEPS - 30:, 1] = 1.0                    # rotor 2 lost in the last 3 s
    late = quad_check(model, commands)
    quiet = quad_check(model, quad_commands(rng, np.ones(4)))
    assert late.named == ("motor_2",) and late.onset_error_s is not None
    assert late.throughout() is None and quiet.throughout() is None and not quiet.named
    for effort in (late, quiet):
        finding = name_by_hypotheses(observed(effort, {}), _replay_detected(60.0),
                                     NONE_EXPLAINS, JUDGING)
        assert finding.component is None and not finding.candidates
        assert "no single-component fault explains it" in finding.notes[-1]


def test_the_tables_candidates_are_narrowed_by_a_weakness_over_the_whole_log():
    """The table reads all four rotors and the gyro (as it did for simulated quadrotors
    whose rotor 1 gave 80 % of its thrust for a whole flight): the shares over the whole log
    name the weak one; without an effort alarm all are kept."""
    finding = replace(_replay_detected(40.0), candidates=(
        "motor_1", "motor_2", "motor_3", "motor_4", "gyro"), hypotheses=NONE_EXPLAINS)
    by_shares = narrowed(observed(_rotor_3_weak_throughout(), {}), finding, (), JUDGING)
    assert by_shares.candidates == ("motor_3",)
    assert by_shares.notes[-1].endswith("its shares match motor_3 weak alone, over the whole "
                                        "log")
    assert narrowed(observed(None, {}), finding, (), JUDGING).candidates == finding.candidates
