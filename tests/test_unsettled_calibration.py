"""Thresholds `calibrate` set on fewer than SETTLED_LOGS normal logs the model was not
trained on rest on as little as those `train` raised: an alarm of the replay alone that
crosses them slightly, or that no single fault explains, is undetermined, and says what the
thresholds rest on; five such logs settle them. An early alarm no single fault explains
gives way to another judge's later event."""

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import cast

from test_shares_rule_out import UNEXPLAINED_TEST
from test_slight_alarm import ALARM, NORMAL, RAISED, _effort_from, _seen

from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.results import Verdict
from auvdiag_cli.engine.settled import SETTLED_LOGS
from auvdiag_cli.engine.slight_alarm import (
    UNSETTLED,
    before_later_judges,
    beyond_slight,
    later_judges_begin,
    too_slight_for,
    unexplained_on,
)
from auvdiag_cli.vehicle.profile import load_profile
from models.card import ModelCard


def _calibrated_on(unseen: int | None, heave_peak: float, effort=None):
    seen = _seen(heave_peak, calibrated=True, effort=effort)
    return replace(seen, model=replace(seen.model, calibration_unseen_logs=unseen))


def test_an_alarm_on_thresholds_few_unseen_logs_set_is_judged_as_an_uncalibrated_ones():
    unnamed = replace(ALARM, candidates=(), hypotheses=UNEXPLAINED_TEST)
    judged = beyond_slight(unnamed, NORMAL, _calibrated_on(1, 2.65), RAISED)
    assert judged.verdict is Verdict.UNDETERMINED
    assert judged.undetermined_because == unexplained_on(UNSETTLED)
    assert ("the thresholds it crossed rest on 1 normal log(s) the model was not trained on"
            in judged.notes[-1])
    assert f"calibrate it on {SETTLED_LOGS} or more normal logs" in judged.notes[-1]
    slight = beyond_slight(ALARM, NORMAL, _calibrated_on(SETTLED_LOGS - 1, 1.16), RAISED)
    assert slight.undetermined_because == too_slight_for(UNSETTLED)
    # Settled: five unseen logs, or a calibration from before the count was kept.
    assert beyond_slight(unnamed, NORMAL, _calibrated_on(SETTLED_LOGS, 2.65), RAISED) \
        == unnamed
    assert beyond_slight(unnamed, NORMAL, _calibrated_on(None, 2.65), RAISED) == unnamed


def test_an_early_alarm_no_single_fault_explains_gives_way_to_a_later_event():
    """The replay crossed clearly at 67.6 s, naming nothing that explains it; the shares
    show thruster 5 weak from 100 s: the verdict is the shares', at their times. An alarm a
    fault explains, or on settled thresholds, stands."""
    judging = cast(Judging, SimpleNamespace(profile=load_profile(Path("bluerov2"))))
    unnamed = replace(ALARM, candidates=(), hypotheses=UNEXPLAINED_TEST)
    seen = _calibrated_on(1, 2.65, effort=_effort_from(100.0, 104.0))
    assert later_judges_begin(seen, unnamed) == 98.0
    judged = before_later_judges(unnamed, NORMAL, seen, RAISED, judging, 98.0)
    assert judged.verdict is Verdict.FAULT and judged.component == "thruster_5"
    assert judged.onset_s == 100.0 and judged.detected_at_s == 104.0
    assert before_later_judges(ALARM, NORMAL, seen, RAISED, judging, 98.0) == ALARM
    settled = _calibrated_on(SETTLED_LOGS, 2.65, effort=_effort_from(100.0, 104.0))
    assert before_later_judges(unnamed, NORMAL, settled, RAISED, judging, 98.0) == unnamed


def test_the_card_counts_the_calibration_logs_the_model_was_not_trained_on():
    document = {"dt_s": 0.1, "signals": {"commands": ["u"], "sensors": [{"name": "y"}]},
                "architecture": {"hidden": 4, "n_commands": 1}}
    assert ModelCard.from_document(document).calibration_unseen_logs is None
    calibrated = {**document, "calibration": {"normal_logs": ["a", "b", "c", "d"],
                                              "in_sample_logs": ["a", "b", "c"]}}
    card = ModelCard.from_document(calibrated)
    assert card.calibration_unseen_logs == 1
    assert card.identity("m").calibration_unseen_logs == 1
