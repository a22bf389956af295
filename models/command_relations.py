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

from models.skill import MIN_SKILL

WINDOW_S = 30.0           # a weakness is persistent; a current or a gust averages out
MIN_WINDOW_S = 5.0        # logs too short for WINDOW_S: windows of half a log, this at least
# A stretch too short for the window is judged over a shorter one too, this share of it (at
# least MIN_WINDOW_S), with thresholds of its own: noisier, it sees a large extra effort only.
SHORTER_WINDOW = 1 / 3
SMOOTHING_S = 1.0         # of the rates that stand for inertia
MIN_DRIVE = 0.1           # an actuator must work at this rms command in a window to be judged
MARGIN = 1.5              # thresholds: this many times the held-out normal peak of |α|
SUBSPACE_ENERGY = 1e-3    # a direction holding less of the commands' energy is not used
SAME_SIGNATURE = 0.98     # cosine above which two actuators' signatures are the same
OPEN_LOOP_RATIO = 2.0     # a log departing this many times the median is not closed loop
OPEN_LOOP_ROUNDS = 3
MIN_SAMPLES_PER_FEATURE = 20


@dataclass(frozen=True)
class RelationLog:
    """One log on the model grid; ``usable`` marks the steps the relation may speak for
    (operating, outside open-loop test sequences)."""

    name: str
    commands: np.ndarray
    sensors: np.ndarray
    usable: np.ndarray
    efforts: np.ndarray | None = None   # the commands, then outputs only the effort reads


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


def _trailing_sum(values: np.ndarray, steps: int) -> np.ndarray:
    total = np.cumsum(values, axis=0)
    total[steps:] = total[steps:] - total[:-steps]
    return total


@dataclass(frozen=True)
class FittedOn:
    """What a relation was learned from."""

    logs: tuple[str, ...] = ()                  # the training logs fitted
    open_loop_left_out: tuple[str, ...] = ()    # training logs left out as open loop
    steps: int = 0                              # usable steps fitted
    heldout: tuple[str, ...] = ()               # the logs that set the thresholds
    heldout_judged_steps: tuple[int, ...] | None = None   # per actuator, in whole windows

    def to_json(self) -> dict[str, object]:
        return {"logs": list(self.logs), "open_loop_left_out": list(self.open_loop_left_out),
                "steps": self.steps, "heldout": list(self.heldout),
                **({} if self.heldout_judged_steps is None
                   else {"heldout_judged_steps": list(self.heldout_judged_steps)})}

    @classmethod
    def from_json(cls, entry: dict[str, Any]) -> "FittedOn":
        judged = entry.get("heldout_judged_steps")
        return cls(tuple(entry.get("logs", [])), tuple(entry.get("open_loop_left_out", [])),
                   int(entry.get("steps", 0)), tuple(entry.get("heldout", [])),
                   None if judged is None else tuple(int(n) for n in judged))


@dataclass(frozen=True)
class RelationWindow:
    """A window of the extra effort and the extra effort allowed over it."""

    steps: int
    thresholds: np.ndarray           # (n_commands,) |α| allowed; NaN: not judged

    def to_json(self) -> dict[str, Any]:
        return {"window_steps": self.steps, "thresholds": _numbers_out(self.thresholds)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "RelationWindow":
        return cls(int(data["window_steps"]), _numbers_in(data["thresholds"]))


def _numbers_out(values: np.ndarray) -> list[float | None]:
    return [None if math.isnan(v) else round(v, 6) for v in values.tolist()]


def _numbers_in(values: list[float | None]) -> np.ndarray:
    return np.asarray([math.nan if v is None else float(v) for v in values], float)


@dataclass(frozen=True)
class CommandRelations:
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

    @property
    def windows(self) -> tuple[RelationWindow, ...]:
        """The main window first, then the shorter ones."""
        return (RelationWindow(self.window_steps, self.thresholds), *self.shorter)

    def window_label(self, index: int) -> str | None:
        """How window ``index`` of `windows` is named (None: the main one)."""
        return None if index == 0 else f"{self.windows[index].steps * self.dt_s:g} s window"

    @property
    def judges_anything(self) -> bool:
        """Some actuator has a threshold over some window."""
        return any(bool(np.isfinite(w.thresholds).any()) for w in self.windows)

    def with_window_thresholds(self, thresholds: Sequence[np.ndarray]) -> "CommandRelations":
        """The same relations with new thresholds, one array per window of `windows`."""
        main, *rest = thresholds
        return replace(self, thresholds=main, shorter=tuple(
            replace(w, thresholds=t) for w, t in zip(self.shorter, rest, strict=True)))

    def too_little_heldout(self, k: int) -> str:
        """Why actuator k has no threshold though its relation has skill: how long the
        held-out logs drove it in whole windows, against one window's length."""
        judged = self.fitted_on.heldout_judged_steps
        steps = None if judged is None else judged[k]
        had = "" if steps is None else f"{steps * self.dt_s:.1f} s, "
        return (f"too little held-out data drove it to set a threshold ({had}needs "
                f"{self.window_steps * self.dt_s:g} s: one window)")

    @property
    def projector(self) -> np.ndarray:
        return self.basis @ self.basis.T

    def group_of(self, k: int) -> tuple[int, ...]:
        return next(g for g in self.groups if k in g)

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

    def extra_effort(self, commands: np.ndarray, sensors: np.ndarray,
                     usable: np.ndarray, window_steps: int | None = None) -> np.ndarray:
        """α per actuator over the window (of ``window_steps``; None: the main one) ending
        at each step, shape (steps, n_commands); NaN where the window holds too few usable
        steps or the actuator barely worked."""
        window = self.window_steps if window_steps is None else window_steps
        product, drive2, _, ok = self._terms(commands, sensors, usable)
        numerator = _trailing_sum(product, window)
        weight = _trailing_sum(drive2, window)
        count = _trailing_sum(ok.astype(float), window)
        norms = np.maximum(np.diag(self.projector), 1e-12)
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
        return {
            "sensor_scale": self.sensor_scale.tolist(), "weights": self.weights.tolist(),
            "basis": self.basis.tolist(), "thresholds": _numbers_out(self.thresholds),
            "skill": _numbers_out(self.skill), "groups": [list(g) for g in self.groups],
            "dt_s": self.dt_s, "window_steps": self.window_steps,
            "smoothing_steps": self.smoothing_steps, "fitted_on": self.fitted_on.to_json(),
            **({"shorter_windows": [w.to_json() for w in self.shorter]} if self.shorter
               else {}),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "CommandRelations":
        """Raises ValueError where a window or an array does not fit the commands."""
        relations = cls(
            np.asarray(data["sensor_scale"], float), np.asarray(data["weights"], float),
            np.asarray(data["basis"], float), _numbers_in(data["thresholds"]),
            _numbers_in(data["skill"]), tuple(tuple(int(i) for i in g) for g in data["groups"]),
            float(data["dt_s"]), int(data["window_steps"]), int(data["smoothing_steps"]),
            FittedOn.from_json(data.get("fitted_on", {})),
            tuple(RelationWindow.from_json(w) for w in data.get("shorter_windows", [])))
        m = relations.weights.shape[1]
        for window in relations.windows:
            if window.steps < 1 or window.thresholds.shape != (m,):
                raise ValueError(f"command relations: a window of {window.steps} steps with "
                                 f"{window.thresholds.size} thresholds for {m} commands")
        if relations.skill.shape != (m,) or relations.basis.shape[0] != m:
            raise ValueError(f"command relations: skill or mixer basis do not fit {m} commands")
        return relations


class RelationsRefused(ValueError):
    """The logs cannot teach the relation; the message says why."""


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
    m = commands.shape[1]
    signatures = [np.outer(commands[:, k], projector[:, k]).ravel() for k in range(m)]
    norms = [float(np.linalg.norm(s)) for s in signatures]
    parent = list(range(m))
    for i in range(m):
        for j in range(i + 1, m):
            if norms[i] > 0 and norms[j] > 0 and float(
                    signatures[i] @ signatures[j]) / (norms[i] * norms[j]) > SAME_SIGNATURE:
                parent[j] = parent[i]
    return tuple(tuple(k for k in range(m) if parent[k] == root)
                 for root in sorted(set(parent)))


def window_for(logs: Sequence[RelationLog], dt_s: float) -> float:
    """WINDOW_S, or half the median log's usable time where logs are shorter than two
    windows (short flights, short runs), never below MIN_WINDOW_S."""
    usable_s = [float(log.usable.sum()) * dt_s for log in logs]
    if not usable_s:
        return WINDOW_S
    return min(WINDOW_S, max(MIN_WINDOW_S, float(np.median(usable_s)) / 2))


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
    window = max(2, round(window_s / dt_s))
    shorter = max(2, round(max(MIN_WINDOW_S, SHORTER_WINDOW * window_s) / dt_s))
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
    actuator, and the extra effort it may show (MARGIN times the held-out peak; NaN where
    less than one window judged it, or its relation has no skill)."""
    m = len(skill)
    efforts = [relations.extra_effort(h.commands, h.sensors, h.usable, window_steps)
               for h in heldout]
    stacked = np.vstack(efforts) if efforts else np.full((0, m), np.nan)
    finite = np.isfinite(stacked)
    peak = np.where(finite, np.abs(stacked), 0.0).max(axis=0, initial=0.0)
    judged = (finite.sum(axis=0) >= window_steps) & (skill >= MIN_SKILL)
    return tuple(finite.sum(axis=0).tolist()), np.where(judged, MARGIN * peak, np.nan)


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
