"""A replay alarm that barely crosses thresholds no calibration set, with every other judge
quiet, decides nothing: the verdict is undetermined and says why. A model used as trained
judges by 1.5 x the g of one held-out log; a normal mission of another noise seed passed
that by 16-18 % on a simulated BlueROV2 (docs/method.md)."""

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import cast

import numpy as np
from helpers import observed

from auvdiag_cli.engine.effort_check import ActuatorEffort, EffortCheck
from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.residuals import Matching
from auvdiag_cli.engine.results import Finding, Observations, Verdict
from auvdiag_cli.engine.settled import SLIGHT
from auvdiag_cli.engine.slight_alarm import (
    TOO_SLIGHT,
    before_later_judges,
    beyond_slight,
    later_judges_begin,
    set_by_logs,
)
from auvdiag_cli.vehicle.profile import load_profile
from models.card import ModelCard

TIME_S = np.arange(0.0, 120.0, 0.1)
NORMAL = Finding(verdict=Verdict.NORMAL, b={"heave": 0, "sway": 0}, notes=("read",))
ALARM = Finding(verdict=Verdict.FAULT, b={"heave": 1, "sway": 0}, onset_s=59.0,
                detected_at_s=67.6, candidates=("thruster_5", "thruster_6"))
RAISED = frozenset({"heave"})       # its threshold the held-out log's, not the profile's


def _seen(heave_peak: float, sway_peak: float = 0.5, calibrated: bool = False,
          effort: EffortCheck | None = None) -> Observations:
    """A BlueROV2 log whose heave g reaches ``heave_peak`` x its 17.72 % threshold at 68 s;
    sway, which the replay does not judge, ``sway_peak`` x its own."""
    g = np.full((TIME_S.size, 2), 5.0)
    g[(TIME_S > 67.0) & (TIME_S < 69.0), 0] = heave_peak * 17.72
    g[(TIME_S > 67.0) & (TIME_S < 69.0), 1] = sway_peak * 15.0
    thresholds = np.tile([17.72, 15.0], (TIME_S.size, 1))
    zeros = np.zeros_like(g)
    seen = observed(effort, {"sway": "the model cannot predict it"}, "bluerov2")
    return replace(seen, model=replace(seen.model, thresholds_calibrated=calibrated),
                   histories=Histories(TIME_S, sensor_names=("heave", "sway"),
                                       matching=Matching(zeros, zeros, g),
                                       thresholds=thresholds))


def test_a_slight_uncorroborated_alarm_of_uncalibrated_thresholds_is_undetermined():
    judged = beyond_slight(ALARM, NORMAL, _seen(1.16, sway_peak=3.0), RAISED)
    assert judged.verdict is Verdict.UNDETERMINED and judged.undetermined_because == TOO_SLIGHT
    assert judged.component is None and judged.candidates == () and judged.notes[0] == "read"
    assert ("an alarm at 67.6 s (it named thruster_5 or thruster_6) is not taken for a fault: "
            "the replay's heave reached 1.16 x its threshold") in judged.notes[-1]
    assert "auvdiag calibrate" in judged.notes[-1]


def test_a_clear_crossing_calibrated_thresholds_or_another_judge_keep_the_fault():
    assert beyond_slight(ALARM, NORMAL, _seen(SLIGHT + 0.01), RAISED) == ALARM
    assert beyond_slight(ALARM, NORMAL, _seen(1.16, calibrated=True), RAISED) == ALARM
    # A threshold its profile's author set (the shipped Twin-Burger's 15 %) is crossed.
    assert beyond_slight(ALARM, NORMAL, _seen(1.16), frozenset()) == ALARM
    thruster = ActuatorEffort("motor_5", "thruster_5", "vertical", 1.08, 1.0, 0.01, 0.08,
                              2.0, None)
    effort = EffortCheck((thruster,), 0.01, 66.0, 62.0, ("thruster_5",), ())
    assert beyond_slight(ALARM, NORMAL, _seen(1.16, effort=effort), RAISED) == ALARM
    assert beyond_slight(NORMAL, NORMAL, _seen(1.16), RAISED) == NORMAL


def test_the_thresholds_training_raised_are_those_above_the_profiles():
    profile = load_profile(Path("bluerov2"))
    mission = dict(profile.thresholds_for("mission"))
    trained = cast(ModelCard, SimpleNamespace(thresholds={
        "mission": {**mission, "heave": mission["heave"] * 1.77, "surge": mission["surge"]}}))
    assert set_by_logs(profile, trained) == {"heave"}
    assert set_by_logs(profile, cast(ModelCard, SimpleNamespace(thresholds=None))) \
        == frozenset()


def test_a_real_log_that_barely_crosses_thresholds_training_raised_is_undetermined(tmp_path):
    """The shipped Twin-Burger model on the normal paper mission, its flow threshold set at
    1/1.1 of the flow's largest g there: where the profile's own threshold lies below (the
    model's was raised from its held-out logs) the alarm is undetermined; where the profile
    set that threshold itself, it stands."""
    import json
    import shutil

    from auvdiag_cli import api
    from models.store import default_model_dir

    profile = api.load_profile("twin_burger")
    log = Path(__file__).resolve().parents[1] / "sample_logs" / "paper-normal"
    shipped = api.diagnose(log, profile, api.load_model(None, profile))
    flow = shipped.histories.sensor_names.index("flow")
    assert shipped.verdict is Verdict.NORMAL
    threshold = round(float(np.nanmax(shipped.histories.matching.g_percent[:, flow])) / 1.1, 3)
    model_dir = tmp_path / "model"
    shutil.copytree(default_model_dir(), model_dir)
    card = json.loads((model_dir / "model.json").read_text())
    card["thresholds"]["mission"]["flow"] = threshold
    (model_dir / "model.json").write_text(json.dumps(card))
    mission = dict(profile.thresholds["mission"])

    def judged(profile_flow: float) -> Finding:
        given = replace(profile, thresholds={**profile.thresholds,
                                             "mission": {**mission, "flow": profile_flow}})
        return api.diagnose(log, given, api.load_model(model_dir, given))

    raised = judged(threshold / 2)
    assert raised.verdict is Verdict.UNDETERMINED and raised.undetermined_because == TOO_SLIGHT
    assert "the replay's flow reached 1.1" in raised.notes[-1]
    assert judged(threshold).verdict is Verdict.FAULT


def _effort_from(onset_s: float, alarm_s: float) -> EffortCheck:
    """The vertical pair's shares matching thruster 5 weak alone, from ``onset_s``."""
    pair = (ActuatorEffort("motor_5", "thruster_5", "vertical", 1.08, 1.0, 0.01, 0.08, 2.0,
                           None),
            ActuatorEffort("motor_6", "thruster_6", "vertical", 0.92, 1.0, 0.01, -0.08, 0.5,
                           None))
    return EffortCheck(pair, 0.01, alarm_s, onset_s, ("thruster_5",), (), "a weak motor",
                       (("thruster_5", 1.0),), onset_error_s=2.0)


def test_a_slight_alarm_before_another_judges_later_event_leaves_the_verdict_to_it():
    """The replay crossed slightly at 68 s; the shares show thruster 5 weak from 100 s: the
    fault is theirs, dated theirs. Where the shares' event began by the replay's detection,
    or the replay crossed clearly before it, the replay's alarm stands."""
    judging = cast(Judging, SimpleNamespace(profile=load_profile(Path("bluerov2"))))
    later = _effort_from(100.0, 104.0)
    seen = _seen(1.16, effort=later)
    assert later_judges_begin(seen, ALARM) == 98.0
    judged = before_later_judges(ALARM, NORMAL, seen, RAISED, judging, 98.0)
    assert judged.verdict is Verdict.FAULT and judged.component == "thruster_5"
    assert judged.detected_at_s == 104.0 and judged.onset_s == 100.0
    assert any("an alarm at 67.6 s (it named thruster_5 or thruster_6) is not taken for a "
               "fault: the replay's heave reached 1.16 x its threshold at most, no other "
               "judge saw anything before 98.0 s, where the other judges' event begins" in n
               for n in judged.notes)
    assert later_judges_begin(_seen(1.16, effort=_effort_from(62.0, 66.0)), ALARM) is None
    clear = before_later_judges(ALARM, NORMAL, _seen(SLIGHT + 0.01, effort=later), RAISED,
                                judging, 98.0)
    assert clear == ALARM
