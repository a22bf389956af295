"""With a handful of normal logs, how large a weakness must be before the effort check can
tell it from normal: the smallest rise of one actuator's share that the whole-log test
judges is said in the training report and in every report, and it is what the check does —
a rotor carrying a little less than it passes, a little more is named."""

import numpy as np
import pytest
from quad_effort import SHARES, quad_check, quad_commands, quad_model

from auvdiag_cli.reports.training import effort_lines
from models.effort import smallest_rise

ONE_WEAK = np.array([1.0, -1 / 3, -1 / 3, -1 / 3])   # motor_1 up, the others down alike


@pytest.mark.parametrize("seed", [0, 3])
def test_the_smallest_rise_said_is_where_the_check_starts_to_judge(seed: int):
    rng = np.random.default_rng(seed)
    model = quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(3)])
    fit, thresholds = model.fits[0], model.thresholds
    assert fit is not None and thresholds is not None
    rise = smallest_rise(fit, thresholds)
    # Three logs trimmed 3 % apart: the spread itself is uncertain, so the rise must be
    # several spreads (the Student-t threshold on (3 - 1)(4 - 1) degrees of freedom).
    assert np.all((rise > 0.05) & (rise < 0.2))
    normal_share = fit.means.mean(axis=0)
    for factor, named in ((0.9, False), (1.1, True)):
        # A log whose shares are the normal ones, motor_1's risen by factor x its smallest
        # rise, the others fallen alike.
        trim = normal_share / SHARES * (1 + factor * rise[0] * ONE_WEAK)
        check = quad_check(model, quad_commands(rng, trim))
        assert (check.named == ("motor_1",)) is named
        assert check.actuators[0].ratio == pytest.approx(factor, abs=0.08)
    # Every report says it, for this log's own steady time (the typical one here).
    quiet = quad_check(model, quad_commands(rng, normal_share / SHARES))
    assert not quiet.named
    assert quiet.actuators[0].judged_from == pytest.approx(rise[0], rel=0.05)
    assert "one weak actuator shows over this log once it carries about" in quiet.describe()


def test_more_normal_logs_lower_it_and_the_training_report_says_by_how_much():
    rng = np.random.default_rng(1)
    model = quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(3)])
    fit, thresholds = model.fits[0], model.thresholds
    assert fit is not None and thresholds is not None
    now, doubled = smallest_rise(fit, thresholds), smallest_rise(fit, thresholds, 6)
    assert np.all(doubled < now)
    (line,) = effort_lines(model)
    assert "one weak actuator is judged once it carries" in line
    assert "with 6 normal logs, about" in line
