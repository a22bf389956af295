"""How well a model predicts each signal, against predictors that need no learning, and the
prediction horizon that suits the vehicle.

Skill of signal i at horizon H, on held-out normal data replayed as diagnosis replays it
(rollouts re-starting every H from a robust start state, `models.rollouts`):

    skill_i = 1 − rms_model_i / min(rms_hold_i, rms_mean_i)

against the naive predictors ("the last value holds", "the training mean"): 1 is a perfect
model, 0 one no better than the better naive predictor, below 0 a worse one. The same ratio
against the least-squares linear model is reported beside it (``versus_linear``): a learned
model should beat it, but a vehicle that is nearly linear lets the linear model predict
almost as well, and that takes no skill away from the learned one.

A signal is judged only when its skill is at least MIN_SKILL = 1/3. Why that number: a
sensor that dies or sticks reads about what "the last value holds" predicts, so the
residual a stuck sensor leaves is about rms_hold, while the normal residual is rms_model.
Calibration sets thresholds at 1.5 x the normal g; a stuck sensor clears that only if
rms_hold / rms_model ≥ 1.5, i.e. skill ≥ 1 − 1/1.5 = 1/3. Below it the model cannot tell a
failed sensor from its own error.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from models.baselines import HoldLast, TrainingMean, fit_linear
from models.rollouts import Rollout, Rollouts, plan_rollouts, replay_plan

MIN_SKILL = 1.0 / 3.0
# Fewer held-out samples of a signal than this and its skill is not trusted (20 s at 10 Hz).
MIN_SCORED_SAMPLES = 200
# Candidate horizons, longest first; None is the paper's free run.
HORIZON_CANDIDATES_S: tuple[float | None, ...] = (None, 120.0, 60.0, 30.0, 15.0, 8.0, 4.0, 2.0)
# The noise in held-out skill figures: a predictor kept over a simpler one must beat it by
# this much, and a horizon is not preferred for a signal that clears MIN_SKILL by less.
SKILL_MARGIN = 0.02


@dataclass(frozen=True)
class ScoringLog:
    """One held-out log on the model grid, with the cuts a diagnosis would make."""

    name: str
    commands: np.ndarray
    sensors: np.ndarray
    cuts: tuple[int, ...] = ()
    # The actuator outputs (`[[outputs]]`), read by the loops that answer their demand
    # (`models.tracking`); None: the profile has none.
    outputs: np.ndarray | None = None


NAIVE = ("hold", "mean")


def _skill_against(model_rms: float, reference_rms: float) -> float:
    if np.isnan(reference_rms) or np.isnan(model_rms):
        return float("nan")                     # no held-out data for this signal
    if reference_rms == 0.0:
        return float("-inf")                    # a signal that never changes
    return 1.0 - model_rms / reference_rms


@dataclass(frozen=True)
class SignalSkill:
    model_rms: float
    baseline_rms: dict[str, float]        # hold, mean, linear
    samples: int = MIN_SCORED_SAMPLES     # held-out samples the figures come from

    @property
    def best_naive(self) -> str:
        return min(NAIVE, key=lambda k: self.baseline_rms[k])

    @property
    def skill(self) -> float:
        return _skill_against(self.model_rms, self.baseline_rms[self.best_naive])

    @property
    def versus_linear(self) -> float:
        return _skill_against(self.model_rms, self.baseline_rms["linear"])

    @property
    def enough_data(self) -> bool:
        return self.samples >= MIN_SCORED_SAMPLES

    @property
    def judged(self) -> bool:
        return self.enough_data and bool(self.skill >= MIN_SKILL)


@dataclass(frozen=True)
class HorizonScore:
    horizon_s: float | None
    signals: dict[str, SignalSkill]
    predictors: dict[str, str] = field(default_factory=dict)   # signal -> predictor kept

    @property
    def judged(self) -> tuple[str, ...]:
        return tuple(name for name, s in self.signals.items() if s.judged)


def _rms(residuals: list[np.ndarray]) -> np.ndarray:
    stacked = np.concatenate(residuals)
    with np.errstate(over="ignore", invalid="ignore"):
        squared = stacked ** 2
    finite = np.isfinite(stacked)
    count = finite.sum(axis=0)
    # A predictor that diverged (the linear fit can) scores infinity, not NaN.
    diverged = (~np.isfinite(stacked) & ~np.isnan(stacked)).any(axis=0)
    total = np.where(finite, squared, 0.0).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(total / count)
    return np.where(diverged, np.inf, np.where(count > 0, rms, np.nan))


def _residual(measured: np.ndarray, predicted: np.ndarray, plan: Sequence[Rollout]
              ) -> np.ndarray:
    """Measured minus predicted; infinite where a rollout predicts NaN for a measured
    sample (a predictor that broke down must not score only where it still gave numbers)."""
    residual = measured - predicted
    replayed = np.zeros(len(measured), bool)
    for r in plan:
        replayed[r.start:r.end] = True
    broken = replayed[:, None] & np.isfinite(measured) & np.isnan(predicted)
    return np.where(broken, np.inf, residual)


def score_horizon(predictors: dict[str, Rollouts], logs: Sequence[ScoringLog],
                  command_scale: np.ndarray, state_scale: np.ndarray,
                  sensor_names: Sequence[str], horizon_steps: int | None,
                  horizon_s: float | None) -> HorizonScore:
    """Skill of ``predictors['model']`` against the others at one horizon."""
    residuals: dict[str, list[np.ndarray]] = {name: [] for name in predictors}
    for log in logs:
        plan = plan_rollouts(log.sensors, log.cuts, horizon_steps)
        for name, predictor in predictors.items():
            predicted = replay_plan(predictor, log.commands, log.sensors, plan,
                                    command_scale, state_scale)
            residuals[name].append(_residual(log.sensors, predicted, plan))
    rms = {name: _rms(parts) for name, parts in residuals.items()}
    samples = np.isfinite(np.concatenate(residuals["model"])).sum(axis=0)
    return HorizonScore(horizon_s, {
        signal: SignalSkill(float(rms["model"][i]),
                            {k: float(v[i]) for k, v in rms.items() if k != "model"},
                            int(samples[i]))
        for i, signal in enumerate(sensor_names)})


def choose_horizon(scores: Sequence[HorizonScore]) -> HorizonScore:
    """The longest horizon at which the most signals are judged (longer horizons let slow
    faults, drifts and weakening thrusters, grow in the residual). Signals that clear the
    bar by SKILL_MARGIN, the noise in held-out skill figures, count first: a horizon must
    not win on a signal that only just scrapes past MIN_SKILL there."""
    def rank(score: HorizonScore) -> tuple[int, int]:
        clear = sum(score.signals[name].skill >= MIN_SKILL + SKILL_MARGIN
                    for name in score.judged)
        return clear, len(score.judged)

    best = max(rank(s) for s in scores)
    return next(s for s in scores if rank(s) == best)


def assess(dynamics: Rollouts, command_scale: np.ndarray, state_scale: np.ndarray,
           training: Sequence[ScoringLog], heldout: Sequence[ScoringLog],
           sensor_names: Sequence[str], dt_s: float,
           horizons_s: Sequence[float | None]) -> list[HorizonScore]:
    """Skill of the learned ``dynamics`` on ``heldout`` at each horizon, against the
    yardsticks fitted on ``training`` (its mean, its least-squares linear model)."""
    training_states = np.concatenate([log.sensors for log in training]) / state_scale
    predictors: dict[str, Rollouts] = {
        "model": dynamics,
        "hold": HoldLast(),
        "mean": TrainingMean(np.nanmean(training_states, axis=0)),
        "linear": fit_linear([log.commands / command_scale for log in training],
                             [log.sensors / state_scale for log in training]),
    }
    return [score_horizon(predictors, heldout, command_scale, state_scale, sensor_names,
                          None if h is None else max(1, round(h / dt_s)), h)
            for h in horizons_s]


def choose_predictors(scores: Mapping[str, Sequence[HorizonScore]]) -> list[HorizonScore]:
    """Per horizon, each signal's best predictor on the held-out data: ``scores`` holds each
    candidate's scores (simplest candidate first, the same horizons in the same order); a
    later candidate replaces an earlier one only by beating it by SKILL_MARGIN."""
    kinds = list(scores)
    combined = []
    for at_horizon in zip(*scores.values(), strict=True):
        signals, kept = {}, {}
        for name in at_horizon[0].signals:
            best = 0
            for k in range(1, len(kinds)):
                if _skill_or_worst(at_horizon[k].signals[name]) > _skill_or_worst(
                        at_horizon[best].signals[name]) + SKILL_MARGIN:
                    best = k
            signals[name], kept[name] = at_horizon[best].signals[name], kinds[best]
        combined.append(HorizonScore(at_horizon[0].horizon_s, signals, kept))
    return combined


def _skill_or_worst(skill: SignalSkill) -> float:
    value = skill.skill
    return value if np.isfinite(value) else float("-inf")
