"""The lower confidence bound of a median (the sign test) and what it changes in the effort
check: four normal logs scattered as Student's t says leave the thresholds as t gives them,
while logs scattered far wider still widen them."""

from dataclasses import replace

import numpy as np
import pytest
from quad_effort import quad_commands, quad_model

from auvdiag_cli.reports.training import effort_lines
from models.effort import EffortGroup, GroupFit, GroupLog, fit_group
from models.effort_thresholds import widening
from models.sign_test import lower_rank, median_lower_bound
from models.student_t import quantile


def test_the_rank_is_the_binomials():
    # P(Binomial(12, 1/2) <= 3) = 299/4096 = 0.073, <= 4: 794/4096 = 0.194
    assert lower_rank(12) == 4
    assert lower_rank(6) == 1           # 1/64 below the smallest; 7/64 below the second
    assert lower_rank(3) == 0           # 1/8: three values cannot bound it at 90 %
    assert median_lower_bound(np.arange(3.0), 3) is None
    # values that are not finite say nothing: bounded on the others, or not at all
    assert median_lower_bound(np.array([np.nan, *np.arange(1.0, 13.0)]), 12) == 4.0
    assert median_lower_bound(np.full(12, np.nan), 12) is None


def test_the_bound_lies_below_the_median_as_often_as_it_says():
    rng = np.random.default_rng(3)
    below = [median_lower_bound(rng.standard_normal(12) + 1.0, 12) for _ in range(4000)]
    share = np.mean([b is not None and b <= 1.0 for b in below])
    assert 0.90 <= share <= 0.96        # 1 - 0.073, the exact coverage of rank 4 of 12


def _fit(rng: np.random.Generator, logs: int, offset_sd: float) -> GroupFit:
    members = 4
    group = EffortGroup("rotors", tuple(f"motor_{i}" for i in range(members)), (1.0,) * members)
    summaries = []
    for i in range(logs):
        offset = rng.normal(0.0, offset_sd, members)
        share = 1.0 + offset - offset.mean()
        summaries.append(GroupLog(f"log{i}", 24.0, 100 * share[None, :], np.array([100.0]),
                                  np.full(members, 0.02 ** 2), 8))
    return fit_group(group, summaries, 0.1, 3.0)


def test_four_logs_scattered_as_t_says_keep_t_thresholds():
    rng = np.random.default_rng(11)
    fits = [_fit(rng, 4, 0.03) for _ in range(60)]
    median_based = [float(np.median(np.abs(f.loo_z))) for f in fits]
    # The median alone passes t's quartile on a good share of such choices by chance …
    assert np.mean(np.array(median_based) > quantile(0.75, 2)) > 0.1
    # … which widened their thresholds; its lower bound passes it on hardly any.
    assert np.mean([widening(f) > 1.0 for f in fits]) <= 0.05


def test_logs_scattered_far_wider_than_t_says_widen_it():
    rng = np.random.default_rng(12)
    fit = _fit(rng, 8, 0.03)
    wide = replace(fit, loo_z=3 * fit.loo_z)
    unjudged = wide.loo_z.copy()
    unjudged[0, 0] = np.nan        # a log whose share could not be judged
    assert np.isfinite(widening(replace(wide, loo_z=unjudged)))
    # widened by the whole of the median's excess, not only by its lower bound's
    assert widening(wide) == pytest.approx(np.median(np.abs(wide.loo_z)) / quantile(0.75, 6))
    assert widening(wide) > 1.5


def test_the_training_report_says_when_the_logs_scatter_wider_than_t():
    rng = np.random.default_rng(5)
    model = quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(8)])
    fit = model.fits[0]
    assert fit is not None and widening(fit) == 1.0
    assert "wide as Student's t says" not in effort_lines(model)[0]
    wide = replace(fit, loo_z=3 * fit.loo_z)
    (line,) = effort_lines(replace(model, fits=(wide,)))
    assert (f"they scatter {widening(wide):.2f} times as wide as Student's t says, past "
            "chance, and the threshold is widened as much") in line
