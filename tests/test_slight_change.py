"""A change-test alarm that crosses thresholds set on fewer than SETTLED_LOGS normal logs by
less than SLIGHT times them, with no other judge beside it, is undetermined and says what
the thresholds rest on; a clear crossing, settled thresholds, a calibration from before the
count was kept, or another judge's alarm keep the fault."""

from dataclasses import replace
from types import SimpleNamespace
from typing import cast

import numpy as np
from test_slight_alarm import NORMAL, TIME_S, _seen

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.effort_naming import ActuatorEffort
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.engine.settled import SETTLED_LOGS, SLIGHT
from auvdiag_cli.engine.slight_change import FEW_CHANGE_LOGS, beyond_slight_change
from auvdiag_cli.jobs.thin_evidence import thin_evidence
from models.card import ModelCard

FOUND = Finding(verdict=Verdict.FAULT, b={"heave": 0, "sway": 1}, onset_s=33.6,
                detected_at_s=34.7, component="dvl_sway")


def _changed(peak: float) -> ChangeCheck:
    """The test judged from 32 s; sway's statistic reached ``peak`` x its threshold for a
    second from 34.7 s, and fell back."""
    ratios = np.full((TIME_S.size, 1), 0.4)
    ratios[TIME_S < 32.0] = np.nan
    ratios[(TIME_S >= 34.7) & (TIME_S < 35.7)] = peak
    return ChangeCheck({"window": {"sway": 6.0}}, {"window": {"sway": 6.0 * peak}}, 32.0,
                       alarm_s=34.7, onset_s=33.6, flagged={"sway": peak},
                       ratio_names=("sway",), ratios=ratios)


def _card(logs: int | None) -> ModelCard:
    return cast(ModelCard, SimpleNamespace(change_logs=logs))


def _judged(peak: float, logs: int | None, effort: EffortCheck | None = None,
            replay_peak: float = 0.5) -> Finding:
    seen = replace(_seen(replay_peak, calibrated=True, effort=effort),
                   change_check=_changed(peak))
    return beyond_slight_change(FOUND, NORMAL, seen, _card(logs))


def test_a_slight_change_alarm_alone_on_few_logs_is_undetermined():
    judged = _judged(1.22, 3)
    assert judged.verdict is Verdict.UNDETERMINED and judged.component is None
    assert judged.undetermined_because == f"an alarm too slight for {FEW_CHANGE_LOGS}"
    assert judged.notes[0] == "read"
    assert ("a change-test alarm at 34.7 s (it named dvl_sway) is not taken for a fault: "
            "sway reached 1.22 x its threshold at most") in judged.notes[-1]
    assert "rest on 3 normal log(s)" in judged.notes[-1]
    assert f"calibrate on {SETTLED_LOGS} or more normal logs" in judged.notes[-1]


def test_a_clear_change_settled_thresholds_or_another_judge_keep_the_fault():
    assert _judged(SLIGHT + 0.01, 3) == FOUND
    assert _judged(1.22, SETTLED_LOGS) == FOUND
    assert _judged(1.22, None) == FOUND         # calibrated before the count was kept
    # The replay crossed its thresholds after the change began: it bears the change out.
    assert _judged(1.22, 3, replay_peak=1.1) == FOUND
    thruster = ActuatorEffort("motor_5", "thruster_5", "vertical", 1.08, 1.0, 0.01, 0.08,
                              2.0, None)
    effort = EffortCheck((thruster,), 0.01, 66.0, 62.0, ("thruster_5",), ())
    assert _judged(1.22, 3, effort=effort) == FOUND
    # A fault the replay found, whatever the change test did.
    seen = replace(_seen(0.5, calibrated=True), change_check=_changed(1.22))
    replayed = replace(FOUND, detected_at_s=67.6)
    assert beyond_slight_change(replayed, NORMAL, seen, _card(3)) == replayed


def test_calibrate_warns_while_the_change_tests_thresholds_rest_on_few_logs():
    warned = thin_evidence([], True, change_logs=3)
    assert any(w.startswith("the change test's thresholds rest on 3 normal log(s)")
               for w in warned)
    settled = thin_evidence([], True, change_logs=SETTLED_LOGS)
    assert not any(w.startswith("the change test's thresholds rest on") for w in settled)
