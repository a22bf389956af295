"""The next moment predicted from the present: what the change test judges.

The replay predicts how the vehicle answers its commands over a horizon of seconds; its error
grows along each rollout and swings with every manoeuvre, which hides a failure that shifts a
signal by two or three spreads. A vehicle under a controller is far better predicted a moment
ahead from its measured state: per signal, least squares on

    x(k+h) - x(k) = [s(k), s(k) - s(k-l), c(k), c(k+h/2), c(k+h), 1] @ W

(s: the measured state, every sensor and the profile's measured inputs, and its recent change
over l = h/2 steps; c: the commands or set points over the interval; h = `AHEAD_S`). A
measured input joins the state, not the commands: its value a moment ahead would carry a
failure's own effect into the prediction (an aircraft's airspeed falls when its engine
stops), where its present value tells how the controller is about to act (an autopilot
pitches and throttles by its airspeed error). Its error is small and steady on a healthy
log, so a failure that changes how the vehicle moves — an engine that stops pushing, a
surface that sticks — stands out against the log's own beginning within seconds
(docs/results.md measures both on the ALFA flights). This is the recursive-least-squares
idea of the fault-detection literature in its simplest form: one fit to the normal logs,
judged within each log. A straight line does not extrapolate: each feature is held within
the range the fit saw (`AheadPredictor.ranges`), as the controller it stands for saturates.
On ALFA one flight whose altitude target is 83 m off in its first sample (the autopilot
taking over) had the fit to the other flights of its day predict a climb of 50 m/s there,
and that one step set the climb's skill, measured on the logs left out, at 0.00 (0.42 held
within range): the change test of a model of that day's flights then left the climb out.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

AHEAD_S = 0.5
CROSS_FOLDS = 5      # groups of logs its skill is measured on, each left out in turn
# Each feature is held within the range the fit saw, widened by this share of its width
# each side: a log a little beyond the others is predicted as the line says, one far
# beyond (a target reset as an autopilot takes over) as the edge of what was seen.
RANGE_MARGIN = 0.25
# A signal the predictor barely beats "no change" on is left out of the change test: its
# error is the signal's own motion, and every manoeuvre would move it.
MIN_AHEAD_SKILL = 0.1
# How far each signal's weights may be shrunk towards "no change" (`_solve`), for a signal
# plain least squares predicts too poorly to be judged (`_shrinkage`).
SHRINKAGE = (0.0, 0.001, 0.01, 0.1, 1.0)


@dataclass(frozen=True)
class AheadPredictor:
    """Each signal predicted ``steps`` ahead (`fit_ahead`)."""

    steps: int
    weights: np.ndarray       # (features, n_sensors), physical units
    skill: Mapping[str, float]   # per signal on held-out data: 1 - rms error / rms change
    inputs: int = 0           # measured inputs in the state (a model fitted before: none)
    # (2, features - 1): each feature's lowest and highest over the rows fitted (the constant
    # aside), widened by RANGE_MARGIN; None: a model fitted before, whose features were never
    # held.
    ranges: np.ndarray | None = None

    @property
    def lag(self) -> int:
        return max(1, self.steps // 2)

    def residual(self, commands: np.ndarray, sensors: np.ndarray,
                 inputs: np.ndarray | None = None, cuts: Sequence[int] = ()) -> np.ndarray:
        """Measured less predicted, on the steps of ``sensors`` (NaN where the prediction
        lacks a sample or reaches across one of ``cuts``); ``inputs``: the measured inputs
        (None: the model has none)."""
        state = _state(sensors, inputs if self.inputs else None)
        rows, features, change = _design(commands, state, sensors.shape[1], self.steps,
                                         self.lag, cuts, each_signal=True)
        if self.ranges is not None:
            features[:, :-1] = np.clip(features[:, :-1], self.ranges[0], self.ranges[1])
        out = np.full(sensors.shape, np.nan)
        out[rows + self.steps] = change - features @ self.weights
        return out

    def to_json(self) -> dict[str, Any]:
        return {"ahead_s_steps": self.steps, "lag_steps": self.lag, "state_inputs": self.inputs,
                "features": "s(k), s(k)-s(k-lag), c(k), c(k+steps//2), c(k+steps), 1 "
                            "(s: the sensors, then the measured inputs)",
                "weights": np.round(self.weights, 9).tolist(),
                "heldout_skill": {n: round(v, 4) for n, v in self.skill.items()},
                **({} if self.ranges is None else {"feature_range": self.ranges.tolist()})}

    @classmethod
    def from_json(cls, entry: Mapping[str, Any], n_commands: int, n_sensors: int,
                  n_inputs: int) -> "AheadPredictor":
        """Raises ValueError where the entry does not fit the model's signals."""
        weights = np.asarray(entry["weights"], dtype=float)
        inputs = int(entry.get("state_inputs", 0))
        if inputs not in (0, n_inputs) or weights.shape != (
                2 * (n_sensors + inputs) + 3 * n_commands + 1, n_sensors):
            raise ValueError(f"ahead predictor weights of shape {weights.shape} with "
                             f"{inputs} inputs do not fit {n_commands} commands, "
                             f"{n_sensors} signals and {n_inputs} inputs")
        ranges = None if "feature_range" not in entry else np.asarray(entry["feature_range"],
                                                                      dtype=float)
        if ranges is not None and (ranges.shape != (2, len(weights) - 1)
                                   or not (ranges[0] <= ranges[1]).all()):
            raise ValueError(f"ahead predictor feature ranges of shape {ranges.shape} do not "
                             f"fit its {len(weights)} features")
        return cls(int(entry["ahead_s_steps"]), weights,
                   {str(k): float(v) for k, v in entry.get("heldout_skill", {}).items()},
                   inputs, ranges)


def _state(sensors: np.ndarray, inputs: np.ndarray | None) -> np.ndarray:
    """The measured state: the sensors, then the measured inputs."""
    return sensors if inputs is None else np.hstack([sensors, inputs])


def _design(commands: np.ndarray, state: np.ndarray, n_sensors: int, steps: int, lag: int,
            cuts: Sequence[int], each_signal: bool = False
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows k that can be predicted (every sample known, no cut inside [k-lag, k+steps]),
    their features and the change x(k+steps) - x(k). With ``each_signal``, a row needs its
    features alone: a signal without a sample at k or k+steps leaves only its own change
    unknown (NaN), not every other signal's."""
    length = len(state)
    k = np.arange(lag, max(lag, length - steps))
    features = np.hstack([state[k], state[k] - state[k - lag], commands[k],
                          commands[k + steps // 2], commands[k + steps],
                          np.ones((len(k), 1))])
    change = state[k + steps, :n_sensors] - state[k, :n_sensors]
    known = np.isfinite(features).all(axis=1)
    if not each_signal:
        known &= np.isfinite(change).all(axis=1)
    for cut in cuts:
        known &= ~((k - lag < cut) & (cut <= k + steps))
    return k[known], features[known], change[known]


@dataclass(frozen=True)
class AheadLog:
    """One normal log as the predictor is fitted to it."""

    commands: np.ndarray
    sensors: np.ndarray
    inputs: np.ndarray | None = None      # the measured inputs (None: the profile has none)
    cuts: Sequence[int] = ()

    @property
    def state(self) -> np.ndarray:
        return _state(self.sensors, self.inputs)


def _weights(logs: Sequence[AheadLog], n_sensors: int, steps: int, lag: int,
             penalties: Sequence[float] = (0.0,)) -> tuple[list[np.ndarray], np.ndarray] | None:
    """Least squares, each log with its own constant (`fit_ahead`), once per shrinkage in
    ``penalties`` (`_solve`), and the range each feature is held within (`RANGE_MARGIN`);
    None where the logs hold too few complete rows."""
    fed = [_fed(log.state) for log in logs]
    parts = [_design(log.commands, np.where(f, log.state, 0.0), n_sensors, steps, lag, log.cuts)
             for log, f in zip(logs, fed, strict=True)]
    if not parts or sum(len(p[0]) for p in parts) < 10 * (parts[0][1].shape[1] + len(parts)):
        return None
    rows_of = np.repeat(np.arange(len(parts)), [len(p[0]) for p in parts])
    constants = np.eye(len(parts))[rows_of]
    seen = np.vstack([p[1][:, :-1] for p in parts])
    features = np.hstack([seen, constants])
    change = np.vstack([p[2] for p in parts])
    weights = [np.zeros((parts[0][1].shape[1], change.shape[1])) for _ in penalties]
    for signal in range(change.shape[1]):
        rows = np.array([f[signal] for f in fed])[rows_of]
        if rows.sum() < 10 * features.shape[1]:
            continue      # too few logs fed it: its weights stay 0 (no skill, not judged)
        fed_logs = np.unique(rows_of[rows])
        for k, solved in enumerate(_solve(features[rows], change[rows, signal], len(parts),
                                          penalties)):
            weights[k][:, signal] = np.append(solved[:-len(parts)],
                                              solved[-len(parts):][fed_logs].mean())
    low, high = seen.min(axis=0), seen.max(axis=0)
    margin = RANGE_MARGIN * (high - low)
    return weights, np.vstack([low - margin, high + margin])


def _solve(features: np.ndarray, change: np.ndarray, constants: int,
           penalties: Sequence[float]) -> list[np.ndarray]:
    """The weights of ``change`` on ``features`` (the last ``constants`` columns the logs'
    own constants) for each shrinkage p: least squares with p x rows x each standardised
    feature's squared weight added (ridge; p = 0: plain least squares), the constants left
    free. A handful of short logs hold too little of how the signals move to pin every
    weight down: a fit left free follows what they happened to hold, and predicts other
    logs worse than "no change" (on three normal ALFA flights, the forward acceleration's
    skill -0.79; shrunk, 0.22)."""
    scale = features[:, :-constants].std(axis=0)
    scale = np.append(np.where(scale > 0, scale, 1.0), np.ones(constants))
    standard = features / scale
    gram, moment = standard.T @ standard, standard.T @ change
    free = np.arange(len(scale)) >= len(scale) - constants
    solved = []
    for penalty in penalties:
        if penalty == 0.0:
            solved.append(np.linalg.lstsq(features, change, rcond=None)[0])
        else:
            ridge = np.where(free, 0.0, penalty * len(change))
            # A log's constant with none of its rows here is zero throughout: lstsq, not
            # solve, leaves it at 0 where the system is singular.
            solved.append(np.linalg.lstsq(gram + np.diag(ridge), moment, rcond=None)[0] / scale)
    return solved


def _errors(predictor: AheadPredictor, logs: Sequence[AheadLog]
            ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each log's prediction error and its sensors (a channel the log never fed: NaN)."""
    held = [np.where(_fed(log.sensors), log.sensors, np.nan) for log in logs]
    return [predictor.residual(log.commands, x, log.inputs)
            for log, x in zip(logs, held, strict=True)], held


def fit_ahead(logs: Sequence[AheadLog], names: Sequence[str], dt_s: float,
              heldout: Sequence[AheadLog] = ()) -> AheadPredictor | None:
    """Least squares on the normal logs; a signal that fit cannot judge has its weights
    shrunk as far as predicts the logs left out best (`_shrinkage`, `_solve`). None where
    the logs hold too few complete rows to fit it. Its skill is measured on ``heldout``
    where given, else on each log from a fit to the others (the logs in up to CROSS_FOLDS
    groups, each left out in turn): a least-squares fit of a few dozen weights to
    thousands of rows needs no logs kept from it, and a skill measured on one or two
    held-out logs swings with what they happened to hold (on ALFA, the forward
    acceleration's 0.08 one fold, 0.25 on the day left out). The shrinkage is chosen on the
    same logs left out: of a handful of settings, the best one's skill there is a little
    better than a log never seen would show.

    Each log has its own constant in the fit: a log's trim, payload or wind offsets the
    changes a little, and one constant for all would bend every weight towards those
    offsets. The predictor keeps their mean (the change test judges a log against its own
    beginning, where a constant cancels). A channel a log never fed (one value throughout:
    a sensor not fitted that day) is, as a feature, only that log's constant again, and its
    own changes there are left out of its fit: they say nothing of how it moves."""
    steps = max(1, round(AHEAD_S / dt_s))
    lag = max(1, steps // 2)
    fitted = _weights(logs, len(names), steps, lag, SHRINKAGE)
    if fitted is None:
        return None
    n_inputs = 0 if not logs or logs[0].inputs is None else logs[0].inputs.shape[1]
    # Per shrinkage: the errors on the logs left out, and their sensors.
    errors: list[list[np.ndarray]] = [[] for _ in SHRINKAGE]
    held: list[np.ndarray] = []
    folds = ([(fitted, heldout)] if heldout else [] if len(logs) < 2 else [
        (_weights([log for i, log in enumerate(logs) if i not in group], len(names), steps,
                  lag, SHRINKAGE), [logs[i] for i in group])
        for group in np.array_split(np.arange(len(logs)), min(CROSS_FOLDS, len(logs)))])
    for others, left_out in folds:
        if others is None:
            continue
        for k, weights in enumerate(others[0]):
            more, sensors = _errors(AheadPredictor(steps, weights, {}, n_inputs, others[1]),
                                    left_out)
            errors[k] += more
        held += sensors
    skills = [_skill(e, held, steps, names) for e in errors]
    chosen = [_shrinkage(name, skills) for name in names]
    weights = np.column_stack([fitted[0][k][:, i] for i, k in enumerate(chosen)])
    return AheadPredictor(steps, weights, {n: skills[k][n] for n, k in zip(
        names, chosen, strict=True) if n in skills[k]}, n_inputs, fitted[1])


def _shrinkage(name: str, skills: Sequence[Mapping[str, float]]) -> int:
    """The index of the shrinkage a signal keeps: plain least squares (the first) where it
    predicts the logs left out well enough to be judged (MIN_AHEAD_SKILL); else the one
    that predicts them best. Shrinking only what plain least squares cannot judge keeps
    the predictor every judged signal's thresholds and detections were measured with:
    shrunk wherever a little better on the logs left out (0.03 on two signals of a model of
    one ALFA day's six flights), the engine failures of the other days were found later
    (delay median 3.2 -> 4.5 s)."""
    values = [s.get(name, -np.inf) for s in skills]
    return 0 if values[0] >= MIN_AHEAD_SKILL else int(np.argmax(values))


def _column_means(values: np.ndarray) -> np.ndarray:
    """Each column's mean over its finite values (0 where it has none)."""
    finite = np.isfinite(values)
    return np.where(finite, values, 0.0).sum(axis=0) / np.maximum(finite.sum(axis=0), 1)


def _fed(sensors: np.ndarray) -> np.ndarray:
    """(signals,) whether the log fed each: more than one value over its samples."""
    finite = np.isfinite(sensors)
    return np.asarray(np.where(finite, sensors, -np.inf).max(axis=0)
                      > np.where(finite, sensors, np.inf).min(axis=0))


def _skill(errors: Sequence[np.ndarray], sensors: Sequence[np.ndarray], steps: int,
           names: Sequence[str]) -> dict[str, float]:
    """1 - rms error / rms change over ``steps``, per signal (NaN where nothing held out).
    Each log's error is taken about its own mean, as the change test takes it: the
    predictor's constant is the training logs' mean, and a log's own offset from it (its
    trim, its wind) cancels against the log's beginning."""
    if not errors:
        return {}
    error = np.vstack([e - _column_means(e) for e in errors])
    change = np.vstack([x[steps:] - x[:-steps] for x in sensors])
    with np.errstate(invalid="ignore", divide="ignore"):
        skill = 1.0 - np.sqrt(np.nanmean(error ** 2, axis=0)) / np.sqrt(
            np.nanmean(change ** 2, axis=0))
    return {n: float(s) for n, s in zip(names, skill, strict=True) if np.isfinite(s)}
