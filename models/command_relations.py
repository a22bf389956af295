"""How a healthy vehicle's commands relate to its motion, learned from normal logs.

Whatever drives the vehicle (a controller holding heading, depth or attitude, or a pilot)
spends, for a given motion, a given effort on each actuator. A thruster that gives less
thrust than it should is driven harder for the same motion: the controller hides the
fault from the motion, the commands carry it. This module learns

- the relation: each command as a least-squares function of the motion the sensors
  measure (values, signed squares, products and smoothed rates: drag and inertia), and
- the mixer's reach: the subspace the commands of normal logs span (a mixer that makes
  three efforts out of six thrusters spans three dimensions).

If actuator k gives (1 - f) of its thrust, the effort lost is about f·c_k along the
direction e_k; the controller puts it back through its mixer, so the commands depart
from the relation by about α·c_k·P·e_k, where P projects on the mixer's subspace and α is
the extra effort asked of k. Over a window, α_k is the least-squares fit of that
signature to the departure. Two actuators whose signatures are the same over normal logs
(e.g. a vectored ROV's diagonally opposite thrusters) cannot be told apart: they form a
group, named together."""

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from models.relation_windows import (
    WINDOW_S,
    FittedOn,
    RelationLog,
    RelationsRefused,
    RelationWindow,
    WindowedRelations,
    groups_of,
    peaks_by_window,
    thresholds_from,
    trailing_sum,
    window_for,
    window_steps_for,
    windows_fields,
)

__all__ = ["WINDOW_S", "CommandRelations", "RelationLog", "RelationsRefused", "fit_relations",
           "window_for"]

SMOOTHING_S = 1.0         # of the rates that stand for inertia
MIN_DRIVE = 0.1           # an actuator must work at this rms command in a window to be judged
SUBSPACE_ENERGY = 1e-3    # a direction holding less of the commands' energy is not used
OPEN_LOOP_RATIO = 2.0     # a log departing this many times the median is not closed loop
OPEN_LOOP_ROUNDS = 3
MIN_SAMPLES_PER_FEATURE = 20


def _rates(x: np.ndarray, dt_s: float, smoothing_steps: int) -> np.ndarray:
    """Centred moving average of the rates, as long as ``x`` even when shorter than the
    average (np.convolve's "same" is not)."""
    rate = np.gradient(x, dt_s, axis=0) if len(x) > 1 else np.zeros_like(x)
    kernel = np.ones(smoothing_steps) / smoothing_steps
    first = smoothing_steps // 2
    return np.column_stack([np.convolve(rate[:, i], kernel, "full")[first:first + len(x)]
                            for i in range(x.shape[1])]).reshape(x.shape)


def motion_features(sensors: np.ndarray, scale: np.ndarray, dt_s: float,
                    smoothing_steps: int) -> np.ndarray:
    """Values, signed squares, pairwise products, smoothed rates and a constant, of the
    sensors in units of their full scale; NaN rows where a sensor is missing."""
    x = sensors / scale
    n = x.shape[1]
    pairs = [x[:, i] * x[:, j] for i in range(n) for j in range(i + 1, n)]
    return np.column_stack([x, x * np.abs(x), *pairs, _rates(x, dt_s, smoothing_steps),
                            np.ones(len(x))])


@dataclass(frozen=True)
class CommandRelations(WindowedRelations):
    sensor_scale: np.ndarray         # (n_sensors,)
    weights: np.ndarray              # (n_features, n_commands)
    basis: np.ndarray                # (n_commands, rank): the mixer's subspace
    thresholds: np.ndarray           # (n_commands,) |α| allowed; NaN: not judged
    skill: np.ndarray                # (n_commands,) 1 - rms departure / rms about the mean
    groups: tuple[tuple[int, ...], ...]
    dt_s: float
    window_steps: int
    smoothing_steps: int
    fitted_on: FittedOn
    # Shorter windows for stretches shorter than the main one (none in older models).
    shorter: tuple[RelationWindow, ...] = ()

    measure = "extra effort"

    def as_loss(self, measured: np.ndarray) -> np.ndarray:
        """With thrust growing as the command's square (as the thrust form takes it), an
        extra α of command makes up for 1 - 1/(1 + α)² of the thrust lost."""
        with np.errstate(invalid="ignore"):
            return np.asarray(1.0 - 1.0 / (1.0 + measured) ** 2)

    def from_loss(self, loss: float) -> float:
        return 1.0 / math.sqrt(1.0 - loss) - 1.0

    def unpredicted(self, k: int) -> str:
        """Why actuator k is not judged where its relation lacks skill (its skill aside)."""
        return "the relation does not predict its commands better than their mean"

    def rests_on(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray,
                 actuators: Sequence[int]) -> tuple[int, ...] | None:
        """Which signals the extra effort rests on: this form cannot tell (None), for any
        sensor misreading the motion makes the controller push on the actuators."""
        return None

    def undriven(self, window_s: float) -> str:
        """Why an actuator with a threshold was not judged in a log."""
        return (f"never driven at {MIN_DRIVE:g} of full scale rms or more through one "
                f"{window_s:g} s window of this log")

    @property
    def projector(self) -> np.ndarray:
        return self.basis @ self.basis.T

    def departure(self, commands: np.ndarray, sensors: np.ndarray) -> np.ndarray:
        """Commands minus what the relation expects for the measured motion (NaN rows where
        a signal is missing)."""
        features = motion_features(sensors, self.sensor_scale, self.dt_s, self.smoothing_steps)
        return commands - features @ self.weights

    def _terms(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per step: c_k (P e_k · d), c_k^2, |P d|^2 (zero where not usable), and which
        steps are usable. The signature s_k = c_k P e_k gives s_k·d = c_k (P e_k · d) and
        |s_k|^2 = c_k^2 P_kk."""
        departure = self.departure(commands, sensors)
        ok = usable & np.isfinite(departure).all(axis=1) & np.isfinite(commands).all(axis=1)
        departure = np.where(ok[:, None], departure, 0.0)
        drive = np.where(ok[:, None], commands, 0.0)
        along = departure @ self.projector
        return drive * along, drive**2, (along * departure).sum(axis=1), ok

    def step_terms(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Per step and actuator, what a span's α sums (steps, n_commands) each: α over a
        span is the first's sum over the second's."""
        product, drive2, _, _ = self._terms(commands, sensors, usable)
        return product, drive2 * self._norms()

    def _norms(self) -> np.ndarray:
        """|P e_k|^2 of each actuator's signature direction, kept off zero."""
        return np.maximum(np.diag(self.projector), 1e-12)

    def extra_effort(self, commands: np.ndarray, sensors: np.ndarray,
                     usable: np.ndarray, window_steps: int | None = None) -> np.ndarray:
        """α per actuator over the window (of ``window_steps``; None: the main one) ending
        at each step, shape (steps, n_commands); NaN where the window holds too few usable
        steps or the actuator barely worked."""
        window = self.window_steps if window_steps is None else window_steps
        product, drive2, _, ok = self._terms(commands, sensors, usable)
        numerator = trailing_sum(product, window)
        weight = trailing_sum(drive2, window)
        count = trailing_sum(ok.astype(float), window)
        norms = self._norms()
        enough = (count >= window / 2)[:, None] & (
            weight >= MIN_DRIVE**2 * np.maximum(count, 1.0)[:, None])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(enough, numerator / (weight * norms), np.nan)

    def explained(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
                  ) -> np.ndarray:
        """Per actuator, the share of the departure (within the mixer's reach) that its
        signature explains over the usable steps given: near 1 when that actuator alone
        lost effort, about 1/m when all commands rose together (a sensor reading the
        motion low makes the controller push on every thruster)."""
        product, drive2, energy, _ = self._terms(commands, sensors, usable)
        with np.errstate(invalid="ignore", divide="ignore"):
            share = product.sum(axis=0) ** 2 / (
                drive2.sum(axis=0) * np.diag(self.projector) * energy.sum())
        return np.nan_to_num(share, nan=0.0)

    def to_json(self) -> dict[str, Any]:
        return {"sensor_scale": self.sensor_scale.tolist(), "weights": self.weights.tolist(),
                "basis": self.basis.tolist(), "smoothing_steps": self.smoothing_steps,
                **self.windows_json()}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "CommandRelations":
        """Raises ValueError where a window or an array does not fit the commands."""
        relations = cls(sensor_scale=np.asarray(data["sensor_scale"], float),
                        weights=np.asarray(data["weights"], float),
                        basis=np.asarray(data["basis"], float),
                        smoothing_steps=int(data["smoothing_steps"]), **windows_fields(data))
        m = relations.weights.shape[1]
        relations.check_windows(m, "command relations")
        if relations.skill.shape != (m,) or relations.basis.shape[0] != m:
            raise ValueError(f"command relations: skill or mixer basis do not fit {m} commands")
        return relations


def _rows(logs: Sequence[RelationLog], scale: np.ndarray, dt_s: float, smoothing: int
          ) -> list[tuple[np.ndarray, np.ndarray]]:
    rows = []
    for log in logs:
        features = motion_features(log.sensors, scale, dt_s, smoothing)
        ok = log.usable & np.isfinite(features).all(axis=1) & np.isfinite(
            log.commands).all(axis=1)
        rows.append((features[ok], log.commands[ok]))
    return rows


def _least_squares(rows: Sequence[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    features = np.vstack([f for f, _ in rows])
    commands = np.vstack([c for _, c in rows])
    weights, *_ = np.linalg.lstsq(features, commands, rcond=None)
    return np.asarray(weights)


def _closed_loop(rows: list[tuple[np.ndarray, np.ndarray]], names: list[str]
                 ) -> tuple[list[int], list[str]]:
    """The logs whose commands follow the motion: open-loop runs (test sequences, command
    steps) depart from a relation fitted on the others far more than the median log. Each
    round refits without the logs left out so far (one open-loop log pulls the fit towards
    itself and can hide another)."""
    kept = [i for i, (_, c) in enumerate(rows) if len(c)]
    for _ in range(OPEN_LOOP_ROUNDS):
        if len(kept) < 3:
            break
        weights = _least_squares([rows[i] for i in kept])
        rms = {i: float(np.sqrt(np.mean((rows[i][1] - rows[i][0] @ weights) ** 2)))
               for i in range(len(rows)) if len(rows[i][1])}
        limit = OPEN_LOOP_RATIO * float(np.median([rms[i] for i in kept]))
        now = [i for i in rms if rms[i] <= limit]
        if now == kept:
            break
        kept = now
    return kept, [names[i] for i in range(len(rows)) if i not in kept]


def _subspace(commands: np.ndarray) -> np.ndarray:
    _, singular, vt = np.linalg.svd(commands, full_matrices=False)
    energy = singular**2 / max(float(np.sum(singular**2)), 1e-300)
    rank = max(1, int((energy > SUBSPACE_ENERGY).sum()))
    return np.asarray(vt[:rank].T)


def _groups(commands: np.ndarray, basis: np.ndarray) -> tuple[tuple[int, ...], ...]:
    """Actuators whose signatures c_k·P·e_k coincide over the data (up to scale)."""
    projector = basis @ basis.T
    return groups_of([np.outer(commands[:, k], projector[:, k]).ravel()
                      for k in range(commands.shape[1])])


def fit_relations(training: Sequence[RelationLog], heldout: Sequence[RelationLog],
                  sensor_scale: Sequence[float], dt_s: float,
                  window_s: float | None = None) -> CommandRelations:
    """Fit on ``training``; thresholds from ``heldout`` (normal logs not fitted on).
    ``window_s``: the extra effort's window (None: `window_for` the logs)."""
    window_s = window_for([*training, *heldout], dt_s) if window_s is None else window_s
    scale = np.asarray(sensor_scale, float)
    smoothing = max(1, round(SMOOTHING_S / dt_s))
    rows = _rows(training, scale, dt_s, smoothing)
    kept, open_loop = _closed_loop(rows, [t.name for t in training])
    rows = [rows[i] for i in kept]
    features = np.vstack([f for f, _ in rows]) if rows else np.empty((0, 0))
    if len(features) < MIN_SAMPLES_PER_FEATURE * max(1, features.shape[1]):
        raise RelationsRefused(f"too little usable data ({len(features)} steps) to learn how "
                               "the commands follow the motion")
    commands = np.vstack([c for _, c in rows])
    basis = _subspace(commands)
    m = commands.shape[1]
    window, shorter = window_steps_for(window_s, dt_s)
    relations = CommandRelations(
        scale, _least_squares(rows), basis, np.full(m, np.nan), np.full(m, np.nan),
        _groups(commands, basis), dt_s, window, smoothing,
        FittedOn(tuple(training[i].name for i in kept), tuple(open_loop), len(features),
                 tuple(h.name for h in heldout)),
        (RelationWindow(shorter, np.full(m, np.nan)),) if 2 * shorter <= window else ())
    skill = _skill(relations, heldout, commands.mean(axis=0))
    judged_steps, thresholds = zip(*(_heldout_thresholds(relations, heldout, w.steps, skill)
                                     for w in relations.windows), strict=True)
    fitted_on = replace(relations.fitted_on, heldout_judged_steps=judged_steps[0])
    return replace(relations.with_window_thresholds(thresholds), skill=skill,
                   fitted_on=fitted_on)


def _heldout_thresholds(relations: CommandRelations, heldout: Sequence[RelationLog],
                        window_steps: int, skill: np.ndarray
                        ) -> tuple[tuple[int, ...], np.ndarray]:
    """Over windows of ``window_steps``: how many steps of the held-out logs judged each
    actuator, and the extra effort it may show (`thresholds_from` their peak of |α|; at
    least the extra command that makes up for the least loss either form judges)."""
    peak, judged = peaks_by_window(relations, heldout, window_steps, len(skill))
    return tuple(judged.tolist()), thresholds_from(peak, judged, window_steps, skill,
                                                   relations.least_judged(window_steps))


def _skill(relations: CommandRelations, heldout: Sequence[RelationLog], mean: np.ndarray
           ) -> np.ndarray:
    """Per command, 1 - rms(departure) / rms(command - training mean) on held-out data: a
    relation that does not explain the commands better than their mean judges nothing."""
    departures, deviations = [], []
    for log in heldout:
        departure = relations.departure(log.commands, log.sensors)
        ok = log.usable & np.isfinite(departure).all(axis=1)
        departures.append(departure[ok])
        deviations.append(log.commands[ok] - mean)
    if not departures or not sum(len(d) for d in departures):
        return np.full(len(mean), np.nan)
    model_rms = np.sqrt(np.mean(np.vstack(departures) ** 2, axis=0))
    mean_rms = np.sqrt(np.mean(np.vstack(deviations) ** 2, axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(1.0 - model_rms / mean_rms)
