"""Thresholds to a false-alarm budget: the laws, the leave-one-log-out check, and
`calibrate --false-alarm-rate` on simulated dives."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.jobs.budget import FalseAlarmBudget, Judge, budget_thresholds
from auvdiag_errors import UsageError
from models.false_alarms import (
    checked_share,
    effective_judges,
    fit_law,
    gumbel_fit,
    judge_share,
)
from models.store import default_model_dir

runner = CliRunner()


@pytest.mark.slow
def test_the_gumbel_fit_recovers_its_law_and_its_threshold_holds_on_new_maxima():
    rng = np.random.default_rng(3)
    location, scale = gumbel_fit(rng.gumbel(4.0, 1.5, 4000))
    assert abs(location - 4.0) < 0.1 and abs(scale - 1.5) < 0.08

    def exceeded(threshold: float) -> float:    # the true law's chance of a new maximum past it
        return float(-np.expm1(-np.exp(-(threshold - 4.0) / 1.5)))

    # Thresholds for 2 % from 15 logs' maxima, over 300 sets of logs: the predictive one is
    # passed 2 % of the time; the plug-in quantile of the fitted law, far more often.
    predictive, plug_in = [], []
    for _ in range(300):
        fit = fit_law(list(rng.gumbel(4.0, 1.5, 15)), "gumbel")
        assert fit is not None
        fitted_location, fitted_scale, _ = fit.params
        predictive.append(exceeded(fit.threshold(0.02)))
        plug_in.append(exceeded(fitted_location - fitted_scale * np.log(-np.log1p(-0.02))))
    assert 0.016 < float(np.mean(predictive)) < 0.024
    assert float(np.mean(plug_in)) > 0.027


def test_a_start_level_is_judged_both_ways_and_missing_values_are_skipped():
    rng = np.random.default_rng(4)
    levels = [*rng.normal(0.0, 0.01, 30), float("nan")]
    fit = fit_law(levels, "student-t")
    assert fit is not None and fit.logs == 30 and np.isnan(fit.loo_tail[-1])
    threshold = fit.threshold(0.05)
    assert 0.015 < threshold < 0.03       # about 2 standard deviations from a mean near 0
    assert fit_law([0.1, 0.2, float("nan")], "student-t") is None       # too few logs


def test_the_share_is_lowered_only_for_a_judge_whose_left_out_logs_show_a_heavier_tail():
    rng = np.random.default_rng(5)
    share = judge_share(0.05, 2)
    assert share == pytest.approx(1 - 0.95 ** 0.5)
    light = fit_law(list(rng.gumbel(1.0, 0.2, 40)), "gumbel")
    heavy = fit_law(list(rng.pareto(1.2, 40) + 1.0), "gumbel")
    assert light is not None and heavy is not None
    assert checked_share(light, share) == share
    lowered = checked_share(heavy, share)
    assert lowered < share
    assert sum(heavy.loo_alarms(lowered)) <= round(share * 40)


def test_judges_that_move_together_share_the_budget_as_fewer_judges():
    """Six judges of one disturbance (each log's peaks move together) count as about one
    (Li and Ji's count gives two), six independent ones as about six: the together ones
    get the larger share each, and a normal log still alarms on any of them at about the
    budget."""
    rng = np.random.default_rng(8)
    common = rng.gumbel(1.0, 0.3, 40)
    together = common + rng.normal(0.0, 0.01, (6, 40))
    assert effective_judges(together) < 2.5
    assert effective_judges(rng.gumbel(1.0, 0.3, (6, 40))) > 4.0
    # One log far out on every judge does not make independent judges look alike.
    apart = rng.gumbel(1.0, 0.3, (6, 40))
    apart[:, 0] = 50.0
    assert effective_judges(apart) > 4.0
    # More judges than logs to tell them apart: those beyond count as independent.
    assert effective_judges(rng.gumbel(1.0, 0.3, (26, 20))) >= 24.0
    judges = [Judge("g", f"s{k}", "mission", tuple(common + rng.normal(0.0, 0.01, 40)))
              for k in range(6)]
    fitted = budget_thresholds(judges, 0, FalseAlarmBudget(0.05), [0.1] * 40)
    assert fitted.share > judge_share(0.05, 3)
    # New normal logs of the same kind alarm on any judge at about the budget.
    fresh = rng.gumbel(1.0, 0.3, 20000)
    alarms = np.zeros(fresh.size, bool)
    for f in fitted.fits:
        alarms |= fresh + rng.normal(0.0, 0.01, fresh.size) >= f.threshold
    assert alarms.mean() < 0.1


def test_a_heavy_tailed_judge_does_not_cost_the_others_their_share():
    rng = np.random.default_rng(6)
    light = Judge("start", "depth", None, tuple(rng.normal(0.0, 0.02, 30)))
    # One start far off (a swell at the surface): the law fitted without it misses it.
    heavy = Judge("start", "roll_rate", None, (*rng.normal(0.0, 0.02, 29), 0.4))
    fitted = budget_thresholds([light, heavy], 0, FalseAlarmBudget(0.02), [0.1] * 30)
    shares = {f.judge.name: f.share for f in fitted.fits}
    assert shares["depth"] == fitted.share > shares["roll_rate"]
    assert [f.judge.name for f in fitted.lowered] == ["roll_rate"]


def test_a_start_law_also_learns_from_the_training_logs_starts():
    """With the training logs' starts beside ten calibration logs, the threshold lands
    nearer the true quantile (1.96 sigma for 5 %, two-sided) than from the ten alone."""
    rng = np.random.default_rng(7)
    errors: dict[str, list[float]] = {"alone": [], "helped": []}
    for _ in range(40):
        calibration = tuple(rng.normal(0.0, 0.02, 10))
        training = tuple(rng.normal(0.0, 0.02, 90))
        for key, more in (("alone", ()), ("helped", training)):
            fitted = budget_thresholds([Judge("start", "depth", None, calibration, more)], 0,
                                       FalseAlarmBudget(0.05), [0.1] * 10)
            assert fitted.logs == 10      # the training starts are not calibration logs
            errors[key].append(abs(fitted.fits[0].threshold - 1.96 * 0.02))
    assert np.mean(errors["helped"]) < 0.6 * np.mean(errors["alone"])


@pytest.mark.parametrize(("text", "rate", "per_hour"), [("0.05", 0.05, False),
                                                        ("0.5/h", 0.5, True),
                                                        (" 2 / h ", 2.0, True)])
def test_a_budget_is_a_share_of_logs_or_a_rate_per_hour(text, rate, per_hour):
    budget = FalseAlarmBudget.parse(text)
    assert (budget.rate, budget.per_hour) == (rate, per_hour)
    if per_hour:
        assert budget.per_log([0.1, 0.2, 0.3]) == pytest.approx(1 - np.exp(-rate * 0.2))


@pytest.mark.parametrize("text", ["abc", "0", "0.5", "-0.1", "1/s"])
def test_a_budget_that_means_nothing_is_refused(text):
    with pytest.raises(UsageError, match="--false-alarm-rate"):
        FalseAlarmBudget.parse(text)


@pytest.mark.slow
def test_calibrate_sets_thresholds_for_a_budget_and_says_how_they_held(make_log, tmp_path):
    model = tmp_path / "model"
    shutil.copytree(default_model_dir(), model)
    normal = [make_log(name, seed) for name, seed in (
        ("paper-normal", 61), ("paper-normal", 62), ("mission-ccw", 61),
        ("mission-large-cw", 61), ("routine-and-mission", 61), ("routine-and-mission", 62))]
    strict, loose = tmp_path / "strict", tmp_path / "loose"
    for target, rate in ((strict, "0.01"), (loose, "0.3")):
        result = runner.invoke(app, ["calibrate", *map(str, normal), "--model", str(model),
                                     "--output", str(target), "--false-alarm-rate", rate])
        assert result.exit_code == 0, result.output
        assert "false-alarm rate of" in result.stdout and "leave one log out:" in result.stdout
    meta = {t: json.loads((t / "model.json").read_text()) for t in (strict, loose)}
    budget = meta[loose]["calibration"]["false_alarm_budget"]
    assert budget["rate"] == 0.3 and budget["per"] == "log"
    assert meta[loose]["calibration"]["false_alarm_rate_upper_95_per_hour"] is None
    fitted = {j["judge"]: j["threshold"] for j in budget["judges"]}
    assert meta[loose]["thresholds"]["mission"]["flow"] == pytest.approx(
        fitted["g flow (mission)"], abs=0.005)
    # A tighter budget never gives a lower threshold, and the mission's are fitted (six
    # logs have it) while the DMS modes, with too little data, keep the margin rule.
    for signal in ("flow", "yaw_rate"):
        assert (meta[strict]["thresholds"]["mission"][signal]
                > meta[loose]["thresholds"]["mission"][signal])
    assert not any("(ZA)" in judge for judge in fitted)
    shown = runner.invoke(app, ["diagnose", str(make_log("paper-flow-sensor-covered", 63)),
                                "--model", str(loose), "--json", "-", "-q"])
    report = json.loads(shown.stdout)
    assert report["component"] == "flow_sensor"
    assert report["model"]["false_alarm_rate"] == {"rate": 0.3, "per": "log"}


def test_calibrate_refuses_a_budget_it_cannot_read_in_one_line(make_log, tmp_path):
    result = runner.invoke(app, ["calibrate", str(make_log("paper-normal", 61)), "--model",
                                 str(default_model_dir()), "--output", str(tmp_path / "m"),
                                 "--false-alarm-rate", "often"])
    assert result.exit_code == 2
    assert "--false-alarm-rate" in result.output and len(result.output.strip().splitlines()) == 1


def test_normal_dives_that_start_alike_do_not_alarm_after_a_budgeted_calibration(tmp_path):
    """Simulated dives all start at rest alike: the start's normal deviations barely
    scatter, and a threshold rounded down below them flagged every normal dive at its
    start. Thresholds round up; the calibration logs stay normal."""
    from auvdiag_cli import api

    samples = Path(__file__).resolve().parents[1] / "sample_logs"
    normal = [samples / name for name in ("paper-normal", "mission-large-cw.mcap",
                                          "mission-large-ccw.bin", "mission-fast-ccw.tlog",
                                          "mission-ccw-db3", "routine-and-mission.bag")]
    model_dir = tmp_path / "model"
    shutil.copytree(default_model_dir(), model_dir)
    profile = api.load_profile()
    model = api.load_model(model_dir, profile)
    result = api.calibrate(normal, profile, model,
                           options=api.CalibrateOptions(budget=FalseAlarmBudget(0.05)))
    assert result.budget is not None and result.budget.in_sample_alarmed == 0
    assert api.diagnose(normal[0], profile, model).verdict == api.Verdict.NORMAL


def _wandering_g(rng: np.random.Generator, logs: int, steps: int = 1200) -> np.ndarray:
    """|a moving average| of white noise: a residual index that wanders, one row per log."""
    width = 30
    total = np.cumsum(rng.normal(0.0, 1.0, (logs, steps + width)), axis=1)
    return np.abs(total[:, width:] - total[:, :-width]) / np.sqrt(width)


def test_with_two_normal_logs_a_g_judge_is_fitted_to_blocks_of_them():
    """Two peaks are too few for a law; twelve blocks of the two logs are not. The
    threshold holds the budget on fresh logs of the same kind without sitting far above
    what it needs; with five logs or more, the law is of the logs' peaks as before."""
    from auvdiag_cli.jobs.budget import BLOCKS_PER_LOG, g_judges

    rng = np.random.default_rng(1)
    calibration = _wandering_g(rng, 2)
    (judge,) = g_judges([{"mission": g[:, None]} for g in calibration], ["mission"],
                        ["depth"], ["depth"])
    assert judge.blocks is not None and len(judge.blocks.peaks) == 2 * BLOCKS_PER_LOG
    fitted = budget_thresholds([judge], 0, FalseAlarmBudget(0.05), [0.03, 0.03])
    (fit,) = fitted.fits
    assert fit.by_block and fit.offered == pytest.approx(1 - 0.95 ** (1 / BLOCKS_PER_LOG))
    fresh = _wandering_g(rng, 4000).max(axis=1)
    assert (fresh >= fit.threshold).mean() <= 0.05
    assert fit.threshold < 1.5 * np.quantile(fresh, 0.95)
    (many,) = g_judges([{"mission": g[:, None]} for g in _wandering_g(rng, 5)], ["mission"],
                       ["depth"], ["depth"])
    assert many.blocks is None
    assert not budget_thresholds([many], 0, FalseAlarmBudget(0.05), [0.03] * 5).fits[0].by_block
