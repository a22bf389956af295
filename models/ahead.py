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
judged within each log.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

AHEAD_S = 0.5


@dataclass(frozen=True)
class AheadPredictor:
    """Each signal predicted ``steps`` ahead (`fit_ahead`)."""

    steps: int
    weights: np.ndarray       # (features, n_sensors), physical units
    skill: Mapping[str, float]   # per signal on held-out data: 1 - rms error / rms change
    inputs: int = 0           # measured inputs in the state (a model fitted before: none)

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
        out = np.full(sensors.shape, np.nan)
        out[rows + self.steps] = change - features @ self.weights
        return out

    def to_json(self) -> dict[str, Any]:
        return {"ahead_s_steps": self.steps, "lag_steps": self.lag, "state_inputs": self.inputs,
                "features": "s(k), s(k)-s(k-lag), c(k), c(k+steps//2), c(k+steps), 1 "
                            "(s: the sensors, then the measured inputs)",
                "weights": np.round(self.weights, 9).tolist(),
                "heldout_skill": {n: round(v, 4) for n, v in self.skill.items()}}

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
        return cls(int(entry["ahead_s_steps"]), weights,
                   {str(k): float(v) for k, v in entry.get("heldout_skill", {}).items()},
                   inputs)


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


def fit_ahead(commands: Sequence[np.ndarray], sensors: Sequence[np.ndarray],
              heldout_commands: Sequence[np.ndarray], heldout_sensors: Sequence[np.ndarray],
              names: Sequence[str], dt_s: float,
              cuts: Sequence[Sequence[int]] | None = None,
              inputs: Sequence[np.ndarray] | None = None,
              heldout_inputs: Sequence[np.ndarray] | None = None) -> AheadPredictor | None:
    """Least squares on the normal logs (one array per log; ``inputs``: each log's measured
    inputs, None: the model has none); None where they hold too few complete rows to fit it.

    Each log has its own constant in the fit: a log's trim, payload or wind offsets the
    changes a little, and one constant for all would bend every weight towards those
    offsets. The predictor keeps their mean (the change test judges a log against its own
    beginning, where a constant cancels). A channel a log never fed (one value throughout:
    a sensor not fitted that day) is, as a feature, only that log's constant again, and its
    own changes there are left out of its fit: they say nothing of how it moves."""
    steps = max(1, round(AHEAD_S / dt_s))
    lag = max(1, steps // 2)
    n_sensors = len(names)
    every_cut = cuts or [()] * len(sensors)
    states = [_state(x, None if inputs is None else i)
              for x, i in zip(sensors, inputs or sensors, strict=True)]
    fed = [_fed(x) for x in states]
    parts = [_design(c, np.where(f, x, 0.0), n_sensors, steps, lag, q)
             for c, x, f, q in zip(commands, states, fed, every_cut, strict=True)]
    if not parts or sum(len(p[0]) for p in parts) < 10 * (parts[0][1].shape[1] + len(parts)):
        return None
    logs = np.repeat(np.arange(len(parts)), [len(p[0]) for p in parts])
    constants = np.eye(len(parts))[logs]
    features = np.hstack([np.vstack([p[1][:, :-1] for p in parts]), constants])
    change = np.vstack([p[2] for p in parts])
    weights = np.zeros((parts[0][1].shape[1], change.shape[1]))
    for signal in range(change.shape[1]):
        rows = np.array([f[signal] for f in fed])[logs]
        if rows.sum() < 10 * features.shape[1]:
            continue      # too few logs fed it: its weights stay 0 (no skill, not judged)
        solved, *_ = np.linalg.lstsq(features[rows], change[rows, signal], rcond=None)
        fed_logs = np.unique(logs[rows])
        weights[:, signal] = np.append(solved[:-len(parts)], solved[-len(parts):][fed_logs].mean())
    n_inputs = 0 if inputs is None else states[0].shape[1] - n_sensors
    fitted = AheadPredictor(steps, weights, {}, n_inputs)
    held = [np.where(_fed(x), x, np.nan) for x in heldout_sensors]
    held_inputs: Sequence[np.ndarray | None] = (
        list(heldout_inputs) if heldout_inputs is not None else [None] * len(held))
    errors = [fitted.residual(c, x, i)
              for c, x, i in zip(heldout_commands, held, held_inputs, strict=True)]
    return AheadPredictor(steps, weights, _skill(errors, held, steps, names), n_inputs)


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
