"""Two parts whose failures explain the log about as well: neither is named over the other
unless another judge names one alone. On a simulated BlueROV2, a normal mission's heave
excursion was "explained" by either vertical thruster weakened to 75 % (1.00-1.05x), and
the first ranked was named: a guess, wrong whichever it was."""

from pathlib import Path
from types import SimpleNamespace
from typing import cast

from helpers import observed

from auvdiag_cli.engine.effort_check import ActuatorEffort, EffortCheck
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.isolation import name_by_hypotheses
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.narrowing import TIED_MARGIN, tied_with
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.engine.weakened_naming import name_weakened
from auvdiag_cli.vehicle.profile import load_profile

PROFILE = load_profile(Path("bluerov2"))
TABLE_READS = Finding(verdict=Verdict.FAULT, b={"heave": 1}, onset_s=59.0, detected_at_s=67.6,
                      component="depth_rate_sensor", candidates=("depth_rate_sensor",))


def _weak(thruster: int, peak: float) -> Hypothesis:
    return Hypothesis(f"thruster_{thruster}", "weakened", peak, 0.75, "thruster")


def _hypotheses(second_peak: float) -> HypothesisTest:
    return HypothesisTest((_weak(6, 0.88), _weak(5, second_peak),
                           Hypothesis("depth_rate_sensor", "dead", 3.1)))


def _vertical_shares(harder: str) -> EffortCheck:
    """The vertical pair's shares matching ``harder`` weak alone, begun at 62 s, seen at 66 s."""
    pair = tuple(ActuatorEffort(f"motor_{i}", f"thruster_{i}", "vertical", 1.0 + d, 1.0, 0.01,
                                d, 2.0 if d > 0 else 0.5, None)
                 for i, d in ((5, 0.08 if harder == "thruster_5" else -0.08),
                              (6, 0.08 if harder == "thruster_6" else -0.08)))
    return EffortCheck(pair, 0.01, 66.0, 62.0, (harder,), (), "a weak motor",
                       ((harder, 1.0),), onset_error_s=4.0)


def test_a_tie_leaves_both_parts_the_candidates():
    test = _hypotheses(0.89)
    assert tied_with(test, test.best) == test.ranked[1]
    found = name_weakened(observed(None, {}, "bluerov2"), TABLE_READS, test.best, test,
                          PROFILE)
    assert found.verdict is Verdict.FAULT and found.component is None
    assert found.candidates == ("thruster_6", "thruster_5") and found.degradation is None
    assert "cannot tell them apart" in found.notes[-1]
    assert "the pattern table reads b as depth_rate_sensor" in found.notes[-1]


def test_a_clear_lead_is_named():
    test = _hypotheses(0.88 * TIED_MARGIN * 1.01)
    assert tied_with(test, test.best) is None
    found = name_weakened(observed(None, {}, "bluerov2"), TABLE_READS, test.best, test,
                          PROFILE)
    assert found.component == "thruster_6" and found.degradation == test.best


def test_the_shares_decide_a_tie_either_way():
    test = _hypotheses(0.89)
    for harder in ("thruster_5", "thruster_6"):
        found = name_weakened(observed(_vertical_shares(harder), {}, "bluerov2"),
                              TABLE_READS, test.best, test, PROFILE)
        assert found.component == harder and found.candidates == (harder,)


def test_a_fitted_bias_is_no_rival_and_the_hypothesis_test_alone_does_not_guess():
    judging = cast(Judging, SimpleNamespace(profile=PROFILE))
    finding = Finding(verdict=Verdict.FAULT, b={"heave": 1}, onset_s=59.0, detected_at_s=67.6)
    biased = HypothesisTest((_weak(6, 0.88), Hypothesis("depth_rate_sensor", "biased", 0.9)))
    assert tied_with(biased, biased.best) is None
    tie = name_by_hypotheses(observed(None, {}, "bluerov2"), finding, _hypotheses(0.89),
                             judging)
    assert tie.component is None and tie.candidates == ("thruster_6", "thruster_5")
