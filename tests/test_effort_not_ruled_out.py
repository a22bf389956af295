"""With fewer than five normal logs, a log in which one rotor carries more of the effort,
past the threshold a 5 % budget would set but short of the model's own, its shares matching
that rotor's weakness, is neither normal nor a fault: the few logs cannot rule the weakness
out, and the verdict says so."""

from dataclasses import replace

import numpy as np
import pytest
from helpers import observed
from quad_effort import SHARES, quad_check, quad_commands, quad_model

from auvdiag_cli.engine.near_effort import not_ruled_out_because, unless_not_ruled_out
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.reports.report_build import _actuators
from auvdiag_cli.reports.training import effort_lines
from models.effort_model import EffortModel
from models.effort_thresholds import NEAR_RATE, logs_to_judge, smallest_rise

ONE_WEAK = np.array([1.0, -1 / 3, -1 / 3, -1 / 3])   # motor_1 up, the others down alike


def _model(logs: int, seed: int = 4) -> EffortModel:
    rng = np.random.default_rng(seed)
    return quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(logs)])


def _between(model: EffortModel, where: float, seed: int = 9) -> np.ndarray:
    """A log whose motor_1 rises ``where`` of the way from the rise the threshold a 5 % budget
    sets judges to the one the model's own judges (0: the first, 1: the second)."""
    fit, thresholds = model.fits[0], model.thresholds
    assert fit is not None and thresholds is not None
    own = smallest_rise(fit, thresholds)[0]
    loose = smallest_rise(fit, replace(thresholds, false_alarm_rate=NEAR_RATE))[0]
    rise = loose + where * (own - loose)
    trim = fit.means.mean(axis=0) / SHARES * (1 + rise * ONE_WEAK)
    return quad_commands(np.random.default_rng(seed), trim)


def test_a_rotor_between_the_two_thresholds_is_not_ruled_out_on_four_logs():
    model = _model(4)
    between = _between(model, 0.5)
    check = quad_check(model, between)
    assert check.alarm_s is None and not check.named
    assert check.not_ruled_out == "motor_1"
    assert check.near_matches[0][0] == "motor_1" and check.near_matches[0][1] >= 0.8
    assert check.describe().startswith("no actuator is past its threshold (closest: motor_1")
    assert "these few normal logs cannot rule out a weak motor_1" in check.describe()
    assert _actuators(check).not_ruled_out == "motor_1"     # the JSON's
    # Under the looser threshold it is normal.
    assert quad_check(model, _between(model, -0.6)).not_ruled_out is None
    # A user whose budget is 5 % is told it is a fault.
    assert model.thresholds is not None
    looser = replace(model, false_alarm_rate=NEAR_RATE,
                     thresholds=replace(model.thresholds, false_alarm_rate=NEAR_RATE))
    alarmed = quad_check(looser, between)
    assert alarmed.named == ("motor_1",) and alarmed.not_ruled_out is None


def test_five_normal_logs_judge_it_normal_or_fault():
    model = _model(5)
    check = quad_check(model, _between(model, 0.5))
    assert check.alarm_s is None and check.not_ruled_out is None
    assert "cannot rule out" not in check.describe()
    (line,) = effort_lines(model)
    assert "cannot rule that weakness out" not in line


def test_training_says_where_the_band_lies():
    model = _model(4)
    assert model.thresholds is not None and model.fits[0] is not None
    (line,) = effort_lines(model)
    near = model.thresholds.near(model.fits[0])
    assert near is not None and near < model.thresholds.whole_log(model.fits[0])
    assert (f"from z {near:.2f} (the threshold of a 5% budget) to it, a log whose shares "
            "match one actuator's weakness is undetermined") in line


@pytest.mark.parametrize("verdict", [Verdict.NORMAL, Verdict.FAULT])
def test_only_a_normal_verdict_becomes_undetermined(verdict: Verdict):
    model = _model(4)
    seen = observed(quad_check(model, _between(model, 0.5)), {})
    finding = unless_not_ruled_out(Finding(verdict=verdict, b={}), seen)
    if verdict is Verdict.FAULT:
        assert finding.verdict is Verdict.FAULT and finding.undetermined_because is None
        return
    assert finding.verdict is Verdict.UNDETERMINED
    assert finding.candidates == ("motor_1",)
    assert finding.undetermined_because == not_ruled_out_because("motor_1")
    assert finding.undetermined_because.startswith("motor_1 may be weak")
    assert "cannot rule out a weak motor_1" in finding.notes[-1]


def test_a_log_not_ruled_out_is_told_how_many_normal_logs_would_judge_it():
    """The count said is the least number of normal logs like the model's (their spread as
    measured: more degrees of freedom, less of the normal share's uncertainty) whose
    threshold the log's statistic passes; one log fewer would not, and a log nearer the
    model's threshold needs fewer."""
    model = _model(4)
    fit, thresholds = model.fits[0], model.thresholds
    assert fit is not None and thresholds is not None
    check = quad_check(model, _between(model, 0.5))
    motor_1 = next(a for a in check.actuators if a.name == "motor_1")
    logs = check.judged_with_logs
    assert logs is not None and logs > fit.logs and logs == motor_1.judged_with_logs
    z = (motor_1.ratio or 0.0) * thresholds.whole_log(fit)

    def passes(count: int) -> bool:
        grown = z * np.sqrt((1 + 1 / fit.logs) / (1 + 1 / count))
        return bool(grown > thresholds.whole_log(fit, fit.dof * (count - 1) / (fit.logs - 1)))

    assert passes(logs) and not passes(logs - 1)
    assert f"about {logs} normal logs like these would judge it" in check.describe()
    assert _actuators(check).not_ruled_out_judged_with_logs == logs     # the JSON's
    nearer = quad_check(model, _between(model, 0.9)).judged_with_logs
    assert nearer is not None and nearer <= logs
    assert logs_to_judge(fit, thresholds, 1.2) is None       # already judged
    finding = unless_not_ruled_out(Finding(verdict=Verdict.NORMAL, b={}),
                                   observed(check, {}))
    assert finding.notes[-1].endswith(f"(about {logs} in all, like these, would)")
