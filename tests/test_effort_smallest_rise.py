"""With a handful of normal logs, how large a weakness must be before the effort check can
tell it from normal: the smallest rise of one actuator's share that the whole-log test
judges is said in the training report and in every report, and it is what the check does —
a rotor carrying a little less than it passes, a little more is named."""

import numpy as np
import pytest
from quad_effort import SHARES, STEPS, quad_check, quad_commands, quad_model

from auvdiag_cli.engine.effort_spans import smallest_later_rise
from auvdiag_cli.engine.effort_words import rise_range
from auvdiag_cli.reports.training import effort_lines
from models.effort_thresholds import smallest_rise

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
    assert quiet.actuators[0].smallest_rise_shown == pytest.approx(rise[0], rel=0.05)
    assert "one weak actuator shows over this log once it carries about" in quiet.describe()


def test_more_normal_logs_lower_it_and_the_training_report_says_by_how_much():
    rng = np.random.default_rng(1)
    model = quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(3)])
    fit, thresholds = model.fits[0], model.thresholds
    assert fit is not None and thresholds is not None
    now, doubled = smallest_rise(fit, thresholds), smallest_rise(fit, thresholds, 6)
    assert np.all(doubled < now)
    (line,) = effort_lines(model)
    assert "one weak actuator is judged once it carries about" in line
    assert "with 6 normal logs, about" in line
    # Against the log's own first half the offset between logs cancels: where logs differ
    # more than a log's own windows do (trims 3 % apart here), a weakness that begins
    # mid-log is judged from a far smaller rise, and the line says so.
    setup = model.setups[0]
    later = smallest_later_rise(setup, fit, thresholds, model.dt_s)
    assert np.all(later < now / 3)
    assert f"where it weakens halfway through such a log, about {rise_range(list(later))}" in line


def test_a_weakness_from_halfway_is_judged_from_about_the_rise_said():
    """The later-start test's smallest rise is where it judges half the logs whose motor_1
    rises that much from halfway (the log's own noise decides either way there); at half of
    it hardly any log is judged, at twice it every one is, named and dated within a window of
    halfway."""
    rng = np.random.default_rng(3)
    model = quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(3)])
    fit, thresholds = model.fits[0], model.thresholds
    assert fit is not None and thresholds is not None
    rise = smallest_later_rise(model.setups[0], fit, thresholds, model.dt_s)[0]
    ratios: dict[float, list[float]] = {}
    named: dict[float, int] = {}
    for factor in (0.5, 1.0, 2.0):
        for _ in range(12):
            commands = quad_commands(rng, fit.means.mean(axis=0) / SHARES)
            commands[STEPS // 2:] *= 1 + factor * rise * ONE_WEAK
            check = quad_check(model, commands)
            ratios.setdefault(factor, []).append(check.actuators[0].ratio or 0.0)
            if check.named == ("motor_1",):
                named[factor] = named.get(factor, 0) + 1
                if factor > 1:
                    assert check.onset_s is not None
                    assert abs(check.onset_s - 60.0) <= model.setups[0].window_s
    assert 0.8 <= float(np.median(ratios[1.0])) <= 1.2
    assert named.get(0.5, 0) <= 2 and named[2.0] == 12
