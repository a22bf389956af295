"""How a healthy vehicle's motion answers each actuator's thrust, learned from normal logs:
the commands against the motion, judged forward.

`models.command_relations` learns each command from the motion. Where a mixer drives more
actuators than the efforts it makes (a vectored ROV's four horizontal thrusters from surge,
sway and yaw), the commands are bound to each other, and on slow missions a weak thruster's
extra command hides among what the mission's mix of turning and going asks. Here the motion
a moment ahead is learned from the present motion and each actuator's thrust, per signal by
least squares on

    x(k+h) - x(k) = [x(k), x(k)|x(k)|, x_i(k) x_j(k), T(k..k+h), 1] @ W

(x: the sensors in units of their full scale; T: each actuator's mean thrust over the
interval, taken as command·|command|, a propeller's thrust growing with the square of its
speed; h = `AHEAD_S`; each log its own constant, a current or a trim). An actuator k that
keeps (1 - γ) of its thrust leaves the motion short of the prediction by γ·s_k, s_k its
predicted part of the change (T_k times its weights); over a window γ_k is the
least-squares fit of that to the error, each signal in units of its own noise: the share of
the thrust lost, 0.3 for a thruster at 70 %. The square is what tells the mixed thrusters
apart: their commands move together, their thrusts do not.

Thresholds: each log is judged by a fit to the others, and an actuator may show 1.5 times
the largest share lost any of them showed (`models.relation_windows`); with three normal
missions of the simulated BlueROV2 that is 25-45 % for its horizontal thrusters, which the
commands learnt from the motion cannot judge at all there (docs/vehicles.md, few normal
logs)."""

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from models.relation_windows import (
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

AHEAD_S = 0.5
# An actuator is judged over a window where its predicted part of the motion's change is,
# rms per step, at least the prediction's own error: below that its thrust is not seen.
MIN_CONTRIBUTION = 1.0
MIN_ROWS_PER_FEATURE = 20
# The main window: longer than the commands' form's (`models.relation_windows.WINDOW_S`),
# for the shortfall of the motion is noisier per step than a command's excess. With three
# normal BlueROV2 missions, a thruster at 70 % was found in 50 of 60 dives over 30 s
# windows (named in 43), in 58 over 45 s (named in 50) and in 58 over 60 s (49), with no
# false alarm on 20 normal dives at any of them.
WINDOW_S = 45.0
# The thrusts' standardised weights are shrunk by this times the rows (`_ridge`): on the
# simulated BlueROV2 its vertical pair's effect was split evenly (0 split it 15:1 and left one
# thruster unjudged; 0.03 judged it, but found fewer weak horizontal thrusters).
RIDGE = 0.01


def thrust(commands: np.ndarray) -> np.ndarray:
    return commands * np.abs(commands)


def _design(commands: np.ndarray, sensors: np.ndarray, scale: np.ndarray, steps: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The steps k + h each row's change ends at, the rows' features (the constant last)
    and the changes, for every k with all of them known."""
    x = sensors / scale
    k = np.arange(max(0, len(x) - steps))
    pairs = [x[k, i] * x[k, j] for i, j in itertools.combinations(range(x.shape[1]), 2)]
    total = np.vstack([np.zeros((1, commands.shape[1])), np.cumsum(thrust(commands), axis=0)])
    mean_thrust = (total[k + steps] - total[k]) / steps
    features = np.column_stack([x[k], x[k] * np.abs(x[k]), *pairs, mean_thrust,
                                np.ones(len(k))])
    change = x[k + steps] - x[k]
    known = np.isfinite(features).all(axis=1) & np.isfinite(change).all(axis=1)
    return k[known] + steps, features[known], change[known]


@dataclass(frozen=True)
class ThrustRelations(WindowedRelations):
    sensor_scale: np.ndarray         # (n_sensors,)
    weights: np.ndarray              # (n_features, n_sensors), the thrusts last but one
    noise: np.ndarray                # (n_sensors,) rms error of the fit, in full scales
    thresholds: np.ndarray           # (n_commands,) share of thrust lost allowed; NaN: not
    skill: np.ndarray                # (n_commands,) on logs left out (`_actuator_skill`)
    groups: tuple[tuple[int, ...], ...]
    dt_s: float
    window_steps: int
    ahead_steps: int
    fitted_on: FittedOn
    shorter: tuple[RelationWindow, ...] = ()

    measure = "thrust lost"

    def as_loss(self, measured: np.ndarray) -> np.ndarray:
        return measured

    def from_loss(self, loss: float) -> float:
        return loss

    def unpredicted(self, k: int) -> str:
        """Why actuator k is not judged where its relation lacks skill (its skill aside)."""
        return ("the motion it drives is not predicted from the thrusts better than by its "
                "mean change")

    def undriven(self, window_s: float) -> str:
        """Why an actuator with a threshold was not judged in a log."""
        return (f"its part of the motion stayed below the prediction's error through every "
                f"{window_s:g} s window of this log")

    def rows(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The usable rows (`_design`): the steps they end at, features, changes."""
        at, features, change = _design(commands, sensors, self.sensor_scale, self.ahead_steps)
        keep = usable[at] & usable[at - self.ahead_steps]
        return at[keep], features[keep], change[keep]

    def parts(self, features: np.ndarray, change: np.ndarray, m: int
              ) -> tuple[np.ndarray, np.ndarray]:
        """The motion's shortfall on these rows (the prediction less the change, in units
        of each signal's noise; (rows, signals)) and each of the ``m`` actuators' predicted
        part of the change, in the same units ((rows, actuators, signals))."""
        first = features.shape[1] - 1 - m
        shortfall = (features @ self.weights - change) / self.noise
        parts = features[:, first:first + m, None] * self.weights[None, first:first + m, :]
        return shortfall, parts / self.noise

    def step_terms(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Per step and actuator, what a span's γ sums (steps, n_commands) each, zero where
        no row ends: the shortfall along its part, and its part's energy; γ over a span is
        the first's sum over the second's."""
        product, energy, _ = self._per_step(commands, sensors, usable)
        return product, energy

    def _per_step(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`step_terms`, and 1 where a row ends (steps,)."""
        n, m = commands.shape
        at, features, change = self.rows(commands, sensors, usable)
        shortfall, parts = self.parts(features, change, m)
        product, energy, count = np.zeros((n, m)), np.zeros((n, m)), np.zeros(n)
        product[at] = np.einsum("rs,rks->rk", shortfall, parts)
        energy[at] = (parts ** 2).sum(axis=2)
        count[at] = 1.0
        return product, energy, count

    def extra_effort(self, commands: np.ndarray, sensors: np.ndarray,
                     usable: np.ndarray, window_steps: int | None = None) -> np.ndarray:
        """γ per actuator over the window (of ``window_steps``; None: the main one) ending
        at each step, shape (steps, n_commands): the share of its thrust the motion did not
        show; NaN where the window holds too few usable steps or the actuator's part of the
        motion was too small to see."""
        window = self.window_steps if window_steps is None else window_steps
        product, energy, count = self._per_step(commands, sensors, usable)
        numerator, weight = trailing_sum(product, window), trailing_sum(energy, window)
        rows = trailing_sum(count, window)
        enough = (rows >= window / 2)[:, None] & (
            weight >= MIN_CONTRIBUTION ** 2 * np.maximum(rows, 1.0)[:, None])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(enough, numerator / weight, np.nan)

    def explained(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray
                  ) -> np.ndarray:
        """Per actuator, its share of the thrust lost that all actuators' parts, fitted
        together over the usable steps given, explain: near 1 when one actuator alone lost
        thrust. Fitted together, a thruster and its mirror across the vehicle (their parts
        alike in two of three motions) are told apart by the third."""
        m = commands.shape[1]
        _, features, change = self.rows(commands, sensors, usable)
        shortfall, parts = self.parts(features, change, m)
        if not len(shortfall):
            return np.zeros(m)
        design = parts.transpose(0, 2, 1).reshape(-1, m)
        lost = np.linalg.lstsq(design, shortfall.reshape(-1), rcond=None)[0]
        shown = np.maximum(lost, 0.0) ** 2 * (design ** 2).sum(axis=0)
        total = float(shown.sum())
        return shown / total if total > 0 else np.zeros(m)

    def rests_on(self, commands: np.ndarray, sensors: np.ndarray, usable: np.ndarray,
                 actuators: Sequence[int]) -> tuple[int, ...]:
        """The signals the thrust these ``actuators`` lost rests on: fitted without a
        signal, their loss over the usable steps falls below half of what it is with it,
        or their part of the motion in the others is less than a twentieth of the whole
        (the loss is then seen through that signal alone: a vertical pair's heave). A
        weak actuator leaves every signal it moves short, each by its part; a sensor
        misreading the motion leaves its own signal alone out of line, and without it
        nothing is lost."""
        m = commands.shape[1]
        _, features, change = self.rows(commands, sensors, usable)
        shortfall, parts = self.parts(features, change, m)
        along = parts[:, list(actuators), :].sum(axis=1)
        energy = (along ** 2).sum(axis=0)
        product = (shortfall * along).sum(axis=0)
        whole = float(product.sum()) / max(float(energy.sum()), 1e-300)
        rests = []
        for s in range(len(energy)):
            left = float(energy.sum() - energy[s])
            if left < energy.sum() / 20 or (float(product.sum() - product[s]) / left
                                           < whole / 2):
                rests.append(s)
        return tuple(rests) if whole > 0 else ()

    def to_json(self) -> dict[str, Any]:
        return {"form": "thrust", "sensor_scale": self.sensor_scale.tolist(),
                "weights": np.round(self.weights, 9).tolist(), "noise": self.noise.tolist(),
                "ahead_steps": self.ahead_steps, **self.windows_json()}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "ThrustRelations":
        """Raises ValueError where a window or an array does not fit the commands."""
        relations = cls(sensor_scale=np.asarray(data["sensor_scale"], float),
                        weights=np.asarray(data["weights"], float),
                        noise=np.asarray(data["noise"], float),
                        ahead_steps=int(data["ahead_steps"]), **windows_fields(data))
        m = len(relations.skill)
        relations.check_windows(m, "thrust relations")
        n = len(relations.sensor_scale)
        if relations.weights.shape != (2 * n + n * (n - 1) // 2 + m + 1, n) or (
                relations.noise.shape != (n,)) or relations.ahead_steps < 1:
            raise ValueError(f"thrust relations: weights of shape {relations.weights.shape} "
                             f"do not fit {n} signals and {m} commands")
        return relations


def _ridge(features: np.ndarray, change: np.ndarray, first: int, m: int) -> np.ndarray:
    """Least squares with the thrusts' weights (columns first..first+m, standardised)
    shrunk by RIDGE x rows: two actuators driven alike (a vectored ROV's vertical pair)
    share their effect evenly instead of one taking all of it and the other none."""
    scale = features.std(axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    standard = features / scale
    penalty = np.zeros(features.shape[1])
    penalty[first:first + m] = RIDGE * len(features)
    solved = np.linalg.lstsq(standard.T @ standard + np.diag(penalty), standard.T @ change,
                             rcond=None)[0]
    return np.asarray(solved / scale[:, None])


def _fit(logs: Sequence[RelationLog], scale: np.ndarray, steps: int
         ) -> tuple[np.ndarray, np.ndarray] | None:
    """Weights and each signal's rms error, each log with its own constant (their mean
    kept); None where the logs hold too few usable rows."""
    parts = []
    for log in logs:
        at, features, change = _design(log.commands, log.sensors, scale, steps)
        keep = log.usable[at] & log.usable[at - steps]
        parts.append((features[keep], change[keep]))
    parts = [p for p in parts if len(p[0])]
    if not parts or sum(len(f) for f, _ in parts) < MIN_ROWS_PER_FEATURE * (
            parts[0][0].shape[1] + len(parts)):
        return None
    m = logs[0].commands.shape[1]
    constants = np.repeat(np.eye(len(parts)), [len(f) for f, _ in parts], axis=0)
    features = np.hstack([np.vstack([f[:, :-1] for f, _ in parts]), constants])
    change = np.vstack([c for _, c in parts])
    solved = _ridge(features, change, parts[0][0].shape[1] - 1 - m, m)
    weights = np.vstack([solved[:-len(parts)], solved[-len(parts):].mean(axis=0)])
    error = change - features @ solved
    return weights, np.maximum(np.sqrt(np.mean(error ** 2, axis=0)), 1e-12)


def _actuator_skill(relations: ThrustRelations, log: RelationLog) -> np.ndarray:
    """Per actuator: 1 - rms error / rms change on ``log`` (not fitted on), over the
    signals it moves, each weighted by how much of its part of the change lies there."""
    m = log.commands.shape[1]
    _, features, change = relations.rows(log.commands, log.sensors, log.usable)
    if not len(change):
        return np.full(m, np.nan)
    shortfall, parts = relations.parts(features, change, m)
    error = shortfall * relations.noise
    signal = 1.0 - np.sqrt(np.mean(error ** 2, axis=0)) / np.maximum(
        np.sqrt(np.mean((change - change.mean(axis=0)) ** 2, axis=0)), 1e-12)
    where = (parts ** 2).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray((where * signal[None, :]).sum(axis=1) / where.sum(axis=1))


def _judged_by_others(relations: ThrustRelations, logs: Sequence[RelationLog]
                      ) -> list[tuple[ThrustRelations, RelationLog]]:
    """Each log with the relations fitted to the other logs."""
    held = []
    for i, log in enumerate(logs):
        others = _fit([g for j, g in enumerate(logs) if j != i], relations.sensor_scale,
                      relations.ahead_steps)
        if others is not None:
            held.append((replace(relations, weights=others[0], noise=others[1]), log))
    return held


def _signatures(relations: ThrustRelations, logs: Sequence[RelationLog]) -> list[np.ndarray]:
    """Each actuator's predicted part of the change over the logs, flattened."""
    m = logs[0].commands.shape[1]
    stacked = []
    for log in logs:
        _, features, change = relations.rows(log.commands, log.sensors, log.usable)
        stacked.append(relations.parts(features, change, m)[1])
    parts = np.concatenate(stacked)
    return [parts[:, k, :].ravel() for k in range(m)]


def fit_thrust_relations(logs: Sequence[RelationLog], sensor_scale: Sequence[float],
                         dt_s: float, window_s: float | None = None) -> ThrustRelations:
    """Fit on all ``logs``; each log is then judged by a fit to the others, and those
    held-out peaks set the thresholds and the skill (a handful of logs gives each a say,
    where one held out would speak for all). Needs two logs at least."""
    scale = np.asarray(sensor_scale, float)
    steps = max(1, round(AHEAD_S / dt_s))
    logs = [log for log in logs if log.usable.sum() > steps]
    fitted = _fit(logs, scale, steps) if len(logs) >= 2 else None
    if fitted is None:
        raise RelationsRefused("too little usable data in two logs or more to learn how the "
                               "motion answers each actuator's thrust")
    window_s = window_for(logs, dt_s, WINDOW_S) if window_s is None else window_s
    window, shorter = window_steps_for(window_s, dt_s)
    m = logs[0].commands.shape[1]
    blank = np.full(m, np.nan)
    relations = ThrustRelations(
        scale, fitted[0], fitted[1], blank, blank, (), dt_s, window, steps,
        FittedOn(tuple(log.name for log in logs), (), int(sum(log.usable.sum() for log in logs)),
                 ("each log judged by a fit to the others",)),
        (RelationWindow(shorter, blank),) if 2 * shorter <= window else ())
    held = _judged_by_others(relations, logs)
    skill = (np.nanmean([_actuator_skill(r, log) for r, log in held], axis=0) if held
             else blank)
    thresholds, judged_steps = [], np.zeros(m)
    for index, w in enumerate(relations.windows):
        peaks = [peaks_by_window(r, [log], w.steps, m) for r, log in held]
        peak = np.max([p for p, _ in peaks], axis=0) if peaks else np.zeros(m)
        judged = np.sum([j for _, j in peaks], axis=0) if peaks else np.zeros(m)
        judged_steps = judged if index == 0 else judged_steps
        thresholds.append(thresholds_from(peak, judged, w.steps, skill,
                                          relations.least_judged(w.steps)))
    fitted_on = replace(relations.fitted_on,
                        heldout_judged_steps=tuple(int(n) for n in judged_steps))
    return replace(relations.with_window_thresholds(thresholds), skill=skill,
                   groups=groups_of(_signatures(relations, logs)), fitted_on=fitted_on)
