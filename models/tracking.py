"""How a closed loop follows its set point: the gain of a rate on the error it answers.

An autopilot turns the error between a set point and the measured value (a desired roll
against the roll) into a rate (the roll rate): the rate a moment later is close to a gain
times the error. A part that gives less than it should (an aileron stuck while the other
still moves) leaves the loop slower: the same error brings less rate. The model of the
closed loop predicts the motion from the set points over a whole log, and a failure that
halves a surface's authority moves its error little against the scatter between logs;
the gain, re-estimated over a window all along the log, is what changes. On ALFA's
single-aileron failures (docs/results.md) the roll rate per radian of roll error fell
from about 1.0 to 0.6-0.75 and stayed there.

A loop may answer an actuator's demand instead of an error (``drive``): the rate per unit of
what the controller asks of a part (the roll rate per unit of aileron deflection asked), its
authority. Where the loop barely departs from its set point (the other aileron makes up
for a stuck one), the controller asks the part for more of the same rate: the authority
falls at the first manoeuvre after a failure. Where two outputs drive one part (a left and
a right aileron), the demand is the one further from neutral at each step: an output held
(an autopilot emulating a stuck surface, a servo at its limit) leaves the other carrying
what was asked, so the demand reads the same whether the surface or its output stuck. Its
gain is fitted on the departures from each window's means: a part has a trim (the
deflection that holds the rate at zero is rarely the output's neutral), which a fit through
zero reads as lost authority wherever little is asked (on ALFA, flights trimmed 15-40 us
off neutral dipped it to nothing in straight flight).

A profile declares the loops (`[[tracking]]`); `train` fits each one's lag and the error
it needs to be judged (`fit_tracking`); the change test judges the gain against the log's
own beginning like any other signal (`engine.change_columns`).
"""

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

WINDOW_S = 10.0       # the gain over this much of the log: a manoeuvre or two
MAX_LAG_S = 1.0       # how late the rate may answer the error
# A window whose error is smaller than this share of the typical window's holds too
# little of the loop's answer to measure its gain: not judged.
FLOOR_SHARE = 0.5
# The lags at which the error foretells the rate (correlation) at least this share as well
# as at the best are candidates; of those, the one whose gain is steadiest is taken. Further
# lags can look steadier only because the rate they pair with the error no longer answers it.
FORETOLD_SHARE = 0.95
# An error larger than all but this share of the normal logs' is left out of the gain: the
# loop saturates there (its surfaces or its rate at their limit), and a hard manoeuvre of a
# healthy vehicle would read as a slower loop. On ALFA: a roll error beyond 31 degrees.
SATURATED_SHARE = 0.02


@dataclass(frozen=True)
class TrackingSpec:
    """One loop a profile declares: ``rate`` answers ``set_point`` - ``measured``, or the
    demand of ``drive``."""

    name: str
    set_point: str | None       # a command (None: the loop answers ``drive``)
    measured: str | None        # a sensor (None: the loop answers ``drive``)
    rate: str | None            # a sensor: the measured value's rate (None: its change)
    moved_by: tuple[str, ...]   # the parts that make the rate
    description: str = ""
    drive: tuple[str, ...] = ()     # outputs or commands: the demand (see the module)
    window_s: float = 0.0           # the gain's window; 0: WINDOW_S


@dataclass(frozen=True)
class TrackingFit:
    """A loop as fitted on normal logs."""

    name: str
    set_point: str | None
    measured: str | None
    rate: str | None
    lag_steps: int          # the error this many steps before the rate it brings
    window_steps: int
    floor: float            # the smallest error rms over a window that is judged
    typical: float          # the gain on normal logs (median over their windows)
    limit: float            # a larger error (in size) is left out: the loop saturates
    drive: tuple[str, ...] = ()

    def gain(self, commands: np.ndarray, sensors: np.ndarray,
             command_names: Sequence[str], sensor_names: Sequence[str], dt_s: float
             ) -> np.ndarray:
        """The gain over the window ending at every step, less the typical one (NaN where
        the window's error is below the floor or half of it is missing). ``commands``: what
        the loop may read as its set point or its drive (the commands, the outputs)."""
        error, rate = _error_and_rate(self, commands, sensors, command_names, sensor_names,
                                      dt_s)
        return _windowed_gain(_within(_lagged(error, self.lag_steps), self.limit), rate,
                              self.window_steps, self.floor, bool(self.drive)) - self.typical

    def to_json(self) -> dict[str, object]:
        return {"name": self.name, "set_point": self.set_point, "measured": self.measured,
                "rate": self.rate, "lag_steps": self.lag_steps,
                "window_steps": self.window_steps, "floor": self.floor,
                "typical": self.typical, "limit": self.limit,
                **({"drive": list(self.drive)} if self.drive else {})}

    @classmethod
    def from_json(cls, entry: Mapping[str, Any]) -> "TrackingFit":
        def named(key: str) -> str | None:
            return None if entry.get(key) is None else str(entry[key])

        return cls(str(entry["name"]), named("set_point"), named("measured"), named("rate"),
                   int(entry["lag_steps"]), int(entry["window_steps"]),
                   float(entry["floor"]), float(entry["typical"]), float(entry["limit"]),
                   tuple(str(n) for n in entry.get("drive", ())))


def demand(outputs: np.ndarray) -> np.ndarray:
    """Per step, of ``outputs`` (steps, n) driving one part, the one further from neutral
    (0), signed; NaN where none is known."""
    size = np.where(np.isfinite(outputs), np.abs(outputs), -1.0)
    picked = outputs[np.arange(len(outputs)), np.argmax(size, axis=1)]
    return np.where((size >= 0).any(axis=1), picked, np.nan)


def _error_and_rate(spec: TrackingSpec | TrackingFit, commands: np.ndarray,
                    sensors: np.ndarray, command_names: Sequence[str],
                    sensor_names: Sequence[str], dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    names = list(command_names)
    if spec.drive:
        # A log read without the outputs (a profile that lacks them) leaves it unjudged.
        read = [names.index(n) for n in spec.drive if n in names]
        error = demand(commands[:, read]) if read else np.full(len(commands), np.nan)
    else:
        assert spec.set_point is not None and spec.measured is not None
        error = (commands[:, names.index(spec.set_point)]
                 - sensors[:, list(sensor_names).index(spec.measured)])
    if spec.rate is not None:
        return error, sensors[:, list(sensor_names).index(spec.rate)]
    assert spec.measured is not None     # a loop on a drive names its rate
    measured = sensors[:, list(sensor_names).index(spec.measured)]
    rate = np.full(len(measured), np.nan)
    rate[1:] = np.diff(measured) / dt_s
    return error, rate


def _lagged(values: np.ndarray, steps: int) -> np.ndarray:
    """``values`` as they were ``steps`` earlier (NaN before the first)."""
    if steps <= 0:
        return values
    out = np.full(len(values), np.nan)
    out[steps:] = values[:-steps]
    return out


def _within(error: np.ndarray, limit: float) -> np.ndarray:
    """The error where its size is within ``limit`` (NaN beyond: the loop saturates)."""
    return np.where(np.abs(error) <= limit, error, np.nan)


def _window_sums(values: np.ndarray, window: int) -> np.ndarray:
    """The sum over the last ``window`` steps at every step (over fewer before)."""
    running = np.concatenate([[0.0], np.cumsum(values)])
    ends = np.arange(1, len(values) + 1)
    return np.asarray(running[ends] - running[np.maximum(ends - window, 0)])


def _windowed_gain(error: np.ndarray, rate: np.ndarray, window: int, floor: float,
                   centred: bool = False) -> np.ndarray:
    """The least-squares gain of ``rate`` on ``error`` over the window ending at every step;
    ``centred``: on their departures from the window's means (a demand has a trim: the
    deflection that holds the rate at zero is rarely the output's neutral)."""
    known = np.isfinite(error) & np.isfinite(rate)
    e, r = np.where(known, error, 0.0), np.where(known, rate, 0.0)
    count = _window_sums(known.astype(float), window)
    cross, energy = _window_sums(e * r, window), _window_sums(e * e, window)
    if centred:
        with np.errstate(invalid="ignore", divide="ignore"):
            mean_e = np.where(count > 0, _window_sums(e, window) / count, 0.0)
            mean_r = np.where(count > 0, _window_sums(r, window) / count, 0.0)
        cross, energy = cross - count * mean_e * mean_r, energy - count * mean_e * mean_e
    judged = (count * 2 >= window) & (energy >= count * floor * floor) & (energy > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(judged, cross / energy, np.nan)


def _window_rms(error: np.ndarray, window: int, centred: bool = False) -> np.ndarray:
    """The error's rms over the window ending at every step (its spread, ``centred``)."""
    known = np.isfinite(error)
    e = np.where(known, error, 0.0)
    count = _window_sums(known.astype(float), window)
    energy = _window_sums(e ** 2, window)
    with np.errstate(invalid="ignore", divide="ignore"):
        if centred:
            energy = energy - _window_sums(e, window) ** 2 / count
        return np.where(count * 2 >= window, np.sqrt(np.maximum(energy, 0.0) / count), np.nan)


def _correlation(pairs: Sequence[tuple[np.ndarray, np.ndarray]], lag: int) -> float:
    """How well the error ``lag`` steps before foretells the rate, pooled over the logs."""
    e = np.concatenate([_lagged(error, lag) for error, _ in pairs])
    r = np.concatenate([rate for _, rate in pairs])
    known = np.isfinite(e) & np.isfinite(r)
    if known.sum() < 3 or np.std(e[known]) == 0 or np.std(r[known]) == 0:
        return -math.inf
    return float(np.corrcoef(e[known], r[known])[0, 1])


def _fit_at(spec: TrackingSpec, pairs: Sequence[tuple[np.ndarray, np.ndarray]], lag: int,
            window: int) -> tuple[TrackingFit, list[np.ndarray]] | None:
    """The loop fitted with the error ``lag`` steps before the rate, and its gain on each
    log less the typical one; None where the logs never move the error."""
    lagged = [_lagged(e, lag) for e, _ in pairs]
    sizes = np.abs(np.concatenate(lagged))
    if not np.isfinite(sizes).any():
        return None
    limit = float(np.nanquantile(sizes, 1.0 - SATURATED_SHARE))
    errors = [_within(e, limit) for e in lagged]
    centred = bool(spec.drive)
    rms = np.concatenate([_window_rms(e, window, centred) for e in errors])
    if not np.isfinite(rms).any() or np.nanmedian(rms) <= 0:
        return None
    floor = FLOOR_SHARE * float(np.nanmedian(rms))
    gains = [_windowed_gain(e, r, window, floor, centred)
             for e, (_, r) in zip(errors, pairs, strict=True)]
    if not any(np.isfinite(g).any() for g in gains):
        return None
    typical = float(np.nanmedian(np.concatenate(gains)))
    fit = TrackingFit(spec.name, spec.set_point, spec.measured, spec.rate, lag, window,
                      round(floor, 6), round(typical, 6), round(limit, 6), spec.drive)
    return fit, [g - fit.typical for g in gains]


def fit_tracking(specs: Sequence[TrackingSpec],
                 logs: Sequence[tuple[np.ndarray, np.ndarray]], command_names: Sequence[str],
                 sensor_names: Sequence[str], dt_s: float,
                 unsteadiness: Callable[[Sequence[np.ndarray]], float] | None = None
                 ) -> list[TrackingFit]:
    """Each loop fitted on normal ``logs`` (commands, sensors): the error floor
    (FLOOR_SHARE of the median window's error rms), the limit beyond which it saturates
    (SATURATED_SHARE), its typical gain, and its lag, up to MAX_LAG_S: of the lags at which
    the error foretells the rate nearly as well as at the best (FORETOLD_SHARE), the one at
    which the normal logs' gains are steadiest by ``unsteadiness`` (of each log's gain less
    the typical; smallest wins), or the best without it. A loop whose logs never move its
    error is left out."""
    fits = []
    for spec in specs:
        window = max(2, round((spec.window_s or WINDOW_S) / dt_s))
        pairs = [_error_and_rate(spec, c, s, command_names, sensor_names, dt_s)
                 for c, s in logs]
        foretold = {lag: _correlation(pairs, lag) for lag in range(round(MAX_LAG_S / dt_s) + 1)}
        best = max(foretold.values())
        lags = [lag for lag, value in foretold.items() if value >= FORETOLD_SHARE * best] \
            if unsteadiness is not None else [max(foretold, key=lambda lag: foretold[lag])]
        candidates = [fit for lag in lags if (fit := _fit_at(spec, pairs, lag, window))]
        if candidates:
            steadiest = candidates[0] if unsteadiness is None else min(
                candidates, key=lambda candidate: unsteadiness(candidate[1]))
            fits.append(steadiest[0])
    return fits
