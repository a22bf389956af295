"""The hypotheses tried follow each part's kind: a thruster, rotor or engine dead or weakened,
a control surface stuck at its trim, where it was, or hard over; each said in its own words
in every report."""

from dataclasses import replace

import numpy as np

from auvdiag_cli import api
from auvdiag_cli.engine.hypotheses import (
    HIGH_LIMIT,
    LOW_LIMIT,
    TRIM,
    WHERE_IT_WAS,
    Hypothesis,
    _stuck_surfaces,
)
from auvdiag_cli.reports.sentences import hypotheses_sentence
from auvdiag_cli.vehicle.profile import profile_text


def test_a_surface_is_held_from_the_onset_where_it_may_have_stuck():
    commands = np.column_stack([np.linspace(-1.0, 1.0, 100), np.full(100, 7.0)])
    commands[40:50, 0] = 0.25                  # where it was just before the onset at 50
    trials = dict((h.stuck_at, (h, c)) for h, c in _stuck_surfaces(
        "elevator", "control_surface", [0], commands, 50))
    assert set(trials) == {TRIM, WHERE_IT_WAS, LOW_LIMIT, HIGH_LIMIT}
    expected = {TRIM: float(np.median(commands[:50, 0])), WHERE_IT_WAS: 0.25,
                LOW_LIMIT: -1.0, HIGH_LIMIT: float(commands[:50, 0].max())}
    for where, (hypothesis, trial) in trials.items():
        assert hypothesis.is_actuator and hypothesis.kind == "stuck"
        assert np.allclose(trial[50:, 0], expected[where])
        np.testing.assert_array_equal(trial[:50], commands[:50])    # untouched before it
        np.testing.assert_array_equal(trial[:, 1], commands[:, 1])  # and the other column
    assert _stuck_surfaces("elevator", "control_surface", [0], commands, 0) == []


def test_each_kind_is_said_in_its_own_words():
    assert Hypothesis("engine", "dead", 0.5, 0.0, "engine").describe() == \
        "engine lost its thrust"
    assert Hypothesis("engine", "weakened", 0.5, 0.5, "engine").describe() == \
        "engine at 50% of its thrust"
    assert Hypothesis("thruster_0", "weakened", 0.5, 0.25, "thruster").describe() == \
        "thruster 0 weakened to 25% thrust"
    assert Hypothesis("rudder", "stuck", 0.5, part="control_surface",
                      stuck_at=TRIM).describe() == "rudder stuck at its trim"
    assert not Hypothesis("gyro", "stuck", 0.5).is_actuator


def test_a_profile_whose_part_is_a_surface_is_tried_stuck_not_weakened(make_log, tmp_path):
    text, _ = profile_text(None)
    declared = 'component = "thruster_0"\n'
    path = tmp_path / "surface.toml"
    path.write_text(text.replace(declared, declared + 'kind = "control_surface"\n', 1))
    profile = api.load_profile(path)
    diagnosis = api.diagnose(make_log("mission-thruster-0-dead", 11), profile,
                             api.load_model(None))
    assert diagnosis.hypotheses is not None
    tried = {(h.component, h.kind) for h in diagnosis.hypotheses.ranked}
    assert ("thruster_0", "stuck") in tried and ("thruster_0", "weakened") not in tried
    assert {("thruster_1", "dead"), ("thruster_1", "weakened")} <= tried
    hypotheses = api.build_report(diagnosis).hypotheses
    assert hypotheses is not None
    stuck = [h for h in hypotheses.ranked if h.component == "thruster_0" and h.kind == "stuck"]
    assert {h.stuck_at for h in stuck} == {TRIM, WHERE_IT_WAS, LOW_LIMIT, HIGH_LIMIT}
    said = hypotheses_sentence(replace(hypotheses, best=stuck[0], runner_up=None))
    assert f"thruster 0 stuck {stuck[0].stuck_at} (" in said
