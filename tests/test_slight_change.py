"""A change-test alarm that crosses thresholds four normal logs set by less than a quarter,
every other judge quiet, decides nothing: the verdict is undetermined and says why. Five
logs, a clear crossing, or another judge's alarm keep the fault."""

from dataclasses import replace

import numpy as np
from helpers import observed
from test_slight_alarm import _effort_from

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.residuals import Matching
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.settled import SETTLED_LOGS, SLIGHT
from auvdiag_cli.engine.slight_change import TOO_SLIGHT_CHANGE, beyond_slight_change

TIME_S = np.arange(0.0, 120.0, 0.1)
NORMAL = Finding(verdict=Verdict.NORMAL, b={"climb": 0, "yaw_rate": 0}, notes=("read",))
FAULT = Finding(verdict=Verdict.FAULT, b={"climb": 1, "yaw_rate": 0}, onset_s=32.0,
                detected_at_s=33.4, component="barometer", candidates=("barometer",))


def _seen(ratio: float, replay_peak: float = 0.7, effort=None) -> Observations:
    """A quadrotor's log whose change test crossed its climb threshold at 33.4 s, its
    largest statistic ``ratio`` times it; the replay's g at most ``replay_peak`` times its
    thresholds."""
    change = ChangeCheck({"window": {"climb": 6.0, "yaw_rate": 6.0}},
                         {"window": {"climb": 6.0 * ratio, "yaw_rate": 2.0}}, 30.0,
                         alarm_s=33.4, onset_s=32.0, flagged={"climb": ratio})
    thresholds = np.tile([30.0, 6.0], (TIME_S.size, 1))
    g = thresholds * replay_peak
    zeros = np.zeros_like(g)
    return replace(observed(effort, {}), change_check=change, histories=Histories(
        TIME_S, sensor_names=("climb", "yaw_rate"), matching=Matching(zeros, zeros, g),
        thresholds=thresholds))


def test_a_slight_change_alone_on_thresholds_few_logs_set_is_undetermined():
    judged = beyond_slight_change(FAULT, NORMAL, _seen(1.07), SETTLED_LOGS - 1)
    assert judged.verdict is Verdict.UNDETERMINED
    assert judged.undetermined_because == TOO_SLIGHT_CHANGE
    assert judged.component is None and judged.notes[0] == "read"
    assert ("a change at 33.4 s (it named barometer) is not taken for a fault: the change "
            "test's climb reached 1.07 x its threshold at most" in judged.notes[-1])
    assert "rest on 4 normal log(s)" in judged.notes[-1]


def test_enough_logs_a_clear_change_or_another_judge_keep_the_fault():
    assert beyond_slight_change(FAULT, NORMAL, _seen(1.07), SETTLED_LOGS) == FAULT
    assert beyond_slight_change(FAULT, NORMAL, _seen(1.07), None) == FAULT
    assert beyond_slight_change(FAULT, NORMAL, _seen(SLIGHT + 0.01), 4) == FAULT
    assert beyond_slight_change(FAULT, NORMAL, _seen(1.07, replay_peak=1.1), 4) == FAULT
    effort = _effort_from(30.0, 34.0)
    assert beyond_slight_change(FAULT, NORMAL, _seen(1.07, effort=effort), 4) == FAULT
    assert beyond_slight_change(NORMAL, NORMAL, _seen(1.07), 4) == NORMAL
