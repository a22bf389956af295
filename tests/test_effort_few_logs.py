"""The effort check with the handful of normal logs a user has: each member's spread between
logs drawn towards its group's keeps the false-alarm budget on new normal logs and judges a
departure of six spreads that one member's own spread from four logs would hide; on the
real quadrotor, four normal flights are enough to find a cut propeller and name it."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from shared_data import SHARED_DATA

from models.effort import (
    EffortGroup,
    GroupFit,
    between_spread,
    fit_group,
    summarise,
    within_and_dof,
)
from models.effort_thresholds import thresholds_for, widening
from models.student_t import quantile

RATE, MEMBERS, LOGS, SIGMA = 0.01, 4, 4, 0.02


def _alarms(departure: np.ndarray, pool: bool, seed: int, trials: int = 4000,
            logs: int = LOGS, shares: bool = False) -> float:
    """The share of new logs with ``departure`` (per member, in σ) that alarm, the spread
    learnt each time from ``logs`` normal logs of a group whose members vary alike
    (``shares``: as shares do, each log's departures summing to zero)."""
    rng = np.random.default_rng(seed)
    members = len(departure)
    floor = np.zeros(members)
    limits: dict[float, float] = {}       # the quantile of each degrees of freedom, once
    alarmed = 0

    def drawn(size: tuple[int, ...]) -> np.ndarray:
        values = rng.normal(0.0, SIGMA, size)
        return values - values.mean(axis=-1, keepdims=True) if shares else values

    for _ in range(trials):
        normal = drawn((logs, members))
        spread, dof = between_spread(normal - normal.mean(axis=0), floor, pool)
        if dof not in limits:
            limits[dof] = quantile(1 - RATE / members, dof)
        limit = limits[dof]
        new = drawn((members,)) + departure * SIGMA
        z = (new - normal.mean(axis=0)) / (spread * np.sqrt(1 + 1 / logs))
        alarmed += bool((z > limit).any())
    return alarmed / trials


def test_pooled_spreads_rest_on_every_members_logs():
    departures = np.array([[0.01, -0.02, 0.0, 0.01], [-0.01, 0.02, 0.01, -0.02],
                           [0.0, 0.0, -0.01, 0.01]])
    spread, dof = between_spread(departures, np.zeros(4))
    own, own_dof = between_spread(departures, np.zeros(4), pool=False)
    # Four members' shares average to one: three of them are free in each of three logs
    # (two degrees of freedom each about their mean).
    assert (own_dof, dof) == (2.0, 6.0)
    group = np.sqrt((departures ** 2).sum() / 8)
    assert np.all(np.abs(spread - group) <= np.abs(own - group))     # drawn towards it
    floored, _ = between_spread(departures, np.full(4, 0.05))
    assert np.allclose(floored, 0.05)


def test_window_noise_is_drawn_towards_the_groups_on_the_free_shares():
    rng = np.random.default_rng(5)
    steps, window = 700, 100            # seven windows a log, too few for long ones
    logs = []
    for _ in range(3):
        effort = 1.0 + rng.normal(0.0, 0.02, (steps, 4)) * np.array([2.0, 1.0, 1.0, 1.0])
        summary = summarise("log", effort, effort.mean(axis=1), np.zeros(steps, int), 1,
                            window, 0.1)
        assert summary is not None and summary.long_var is None
        logs.append(summary)
    own_dof = sum(g.windows - 1 for g in logs)
    own = np.sum([g.within_var * (g.windows - 1) for g in logs], axis=0) / own_dof
    within, dof = within_and_dof(logs)
    assert dof == own_dof * 3                       # three of four shares are free
    group = np.mean(own)
    # each member's between its own and the group's, a quarter of the way from the group's
    assert np.allclose(within ** 2 - group, (own - group) / 4)
    assert within[0] == within.max()               # the noisier member stays the noisiest


def test_one_groups_scatter_widens_only_its_own_threshold():
    rng = np.random.default_rng(6)
    steps, window = 700, 100

    def group(name: str, offsets: float) -> GroupFit:
        logs = []
        for _ in range(6):
            effort = (1.0 + rng.normal(0.0, offsets, 2) + rng.normal(0.0, 0.02, (steps, 2)))
            summary = summarise(name, effort, effort.mean(axis=1), np.zeros(steps, int), 1,
                                window, 0.1)
            assert summary is not None
            logs.append(summary)
        return fit_group(EffortGroup(name, ("a", "b"), (1.0, 1.0)), logs, 0.5, window * 0.1)

    quiet, scattered = group("quiet", 0.0), group("scattered", 0.05)
    scattered = replace(scattered, loo_z=3 * scattered.loo_z)   # far wider than t says
    thresholds = thresholds_for([quiet, scattered], RATE)
    assert widening(scattered) > 1.5 and widening(quiet) == 1.0
    share = 0.8 * RATE / 4
    assert thresholds.whole_log(quiet) == pytest.approx(quantile(1 - share, quiet.dof))
    assert thresholds.whole_log(scattered) == pytest.approx(
        widening(scattered) * quantile(1 - share, scattered.dof))


def test_a_pair_learnt_from_three_logs_keeps_its_budget():
    # Two shares that average to one move as one: their spreads drawn together rest on no
    # more than either's own (two degrees of freedom); claimed on twice that, three times
    # the budget alarmed.
    assert _alarms(np.zeros(2), pool=True, seed=3, logs=3, shares=True) < 1.5 * RATE


def test_four_normal_logs_keep_the_budget_and_judge_six_spreads():
    # Normal logs: the budget is kept (within the sampling error of 4000 trials).
    assert _alarms(np.zeros(MEMBERS), pool=True, seed=1) < 1.5 * RATE
    # One member six spreads up: a member's own spread (3 degrees of freedom) hides it
    # most of the time; drawn towards the group's, it is judged most of the time.
    weak = np.array([6.0, 0.0, 0.0, 0.0])
    own = _alarms(weak, pool=False, seed=2, trials=1000)
    pooled = _alarms(weak, pool=True, seed=2, trials=1000)
    assert own < 0.45 and pooled > 0.8


@pytest.mark.shared_data("crazypad/labels.csv")
def test_four_normal_crazypad_flights_find_a_cut_propeller_and_name_motor_3():
    from auvdiag_cli.engine.effort_check import check_effort
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.jobs.effort import effort_log
    from auvdiag_cli.jobs.relate import relation_log
    from auvdiag_cli.vehicle.profile import load_profile
    from models.effort_model import learn_effort

    profile = load_profile(Path("crazyflie"))
    root = SHARED_DATA / "crazypad" / "E8"

    def read(folder: str) -> list:
        return [relation_log(ingest(p, profile), profile)
                for p in sorted((root / folder).glob("*.csv"))]

    normal = read("normal_flight")
    model, _ = learn_effort(profile.effort_groups, [effort_log(g, profile) for g in normal[:4]],
                            profile.dt_s)
    assert model is not None

    def named(log) -> tuple[str, ...]:  # type: ignore[no-untyped-def]
        return check_effort(model, profile, log.commands, log.usable,
                            profile.dt_s * np.arange(len(log.commands))).named

    assert [named(log) for log in normal[4:]] == [()] * (len(normal) - 4)
    cut = read("cut_propeller_M3_3mm_3mm_41mm") + read("cut_propeller_M3_3.5mm_3.5mm_40mm")
    assert cut and all(named(log) == ("motor_3",) for log in cut)
