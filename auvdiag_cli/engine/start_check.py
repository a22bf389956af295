"""The start of a log against the starts of normal logs. The replay starts from the
measured state, so a sensor that reads wrong from the first sample (a depth sensor's zero
shifted, a gyro's bias) is taken as the truth and never shows in g. A log recorded from
rest (every command at zero on its first step) is compared with the normal logs recorded
from rest: at the surface, still, their sensors read alike. A log that begins mid-dive
(its commands already working) is not judged: its start says nothing."""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from models.card import StartReference

SPAN_S = 1.0                 # the start reading: median over this much of the log's start
MARGIN = 1.5                 # thresholds: this many times the largest held-out deviation
FLOOR = 0.05                 # of the full scale: a zero error below it is tolerated
ALIKE = 0.05                 # of the full scale: the most the normal starts may spread
                             # (standard deviation: a few starts far off, in a swell at the
                             # surface, count) for a sensor's start to be judged
MIN_HELDOUT = 3              # held-out starts from rest needed to set a threshold
REST = 0.02                  # a command this close to zero is at rest


@dataclass(frozen=True)
class StartReading:
    sensors: np.ndarray      # (n_sensors,) median over the span; NaN where not logged


def start_reading(commands: np.ndarray, sensors: np.ndarray, dt_s: float
                  ) -> StartReading | None:
    """The first SPAN_S from the first step where every sensor is logged, if every command
    is at rest on that step; None otherwise, or when the span is mostly missing."""
    complete = np.flatnonzero(np.isfinite(sensors).all(axis=1))
    if not complete.size:
        return None
    first = int(complete[0])
    if not (np.abs(commands[first]) <= REST).all():
        return None
    window = sensors[first:first + max(1, round(SPAN_S / dt_s))]
    if np.isfinite(window).all(axis=1).sum() < len(window) / 2:
        return None
    with np.errstate(all="ignore"):
        return StartReading(np.nanmedian(window, axis=0))


def learn_start_state(training: Sequence[StartReading | None],
                      heldout: Sequence[StartReading | None], full_scale: Sequence[float]
                      ) -> StartReference:
    """Where normal logs recorded from rest start (median of the training starts), and per
    sensor how far a start may lie from it (MARGIN x the largest held-out deviation, at
    least FLOOR of the full scale; None where the training starts spread more than ALIKE of
    the full scale), or why there is none."""
    train = [r for r in training if r is not None]
    held = [r for r in heldout if r is not None]
    if not train or len(held) < MIN_HELDOUT:
        return StartReference(refused=f"needs normal logs recorded from rest, held out, to "
                                      f"set how far a start may lie ({len(held)} held out, "
                                      f"needs {MIN_HELDOUT})")
    starts = np.array([r.sensors for r in train])
    reference = np.median(starts, axis=0)
    scale = np.asarray(full_scale, float)
    # A sensor whose normal starts scatter (body rates in a swell) says nothing at the start.
    spread = np.sqrt(np.mean((starts - reference) ** 2, axis=0))
    deviation = np.abs(np.array([r.sensors for r in held]) - reference).max(axis=0)
    allowed = np.where(spread <= ALIKE * scale, np.maximum(MARGIN * deviation, FLOOR * scale),
                       np.nan)
    return StartReference(
        reference=tuple(reference.round(6).tolist()),
        thresholds=tuple(None if np.isnan(a) else round(float(a), 6) for a in allowed),
        training_starts=tuple(tuple(round(float(v), 6) if np.isfinite(v) else None
                                    for v in row) for row in starts),
        span_s=SPAN_S, spread=tuple(spread.round(6).tolist()), logs=len(train),
        heldout_logs=len(held))


def raise_thresholds(start: StartReference, readings: Sequence[StartReading | None],
                     margin: float) -> tuple[StartReference, list[int]]:
    """``start`` with each sensor's threshold raised to ``margin`` times the deviation of
    these normal logs' starts where that is more, and the sensors raised."""
    thresholds = list(start.thresholds)
    reference = np.asarray(start.reference)
    raised = []
    for reading in readings:
        if reading is None or not start.usable:
            continue
        for i, deviation in enumerate(np.abs(reading.sensors - reference)):
            allowed = thresholds[i]
            if allowed is not None and margin * deviation > allowed:
                thresholds[i] = round(float(margin * deviation), 6)
                raised.append(i)
    return replace(start, thresholds=tuple(thresholds)), sorted(set(raised))


@dataclass(frozen=True)
class StartCheck:
    judged: bool
    why_not: str | None
    deviation: dict[str, float]          # start reading minus the normal start, per sensor
    thresholds: dict[str, float]
    off: tuple[str, ...]                 # sensors whose start lies beyond their threshold
    at_s: float | None                   # end of the start span

    def describe(self, units: Mapping[str, str]) -> str:
        if not self.judged:
            return f"not judged ({self.why_not})"
        if not self.off:
            return "every sensor started where normal logs start"
        return "; ".join(f"{name} started {self.deviation[name]:+.3g} {units.get(name, '')} "
                         f"from where normal logs start (allowed {self.thresholds[name]:.3g})"
                         for name in self.off)


def check_start(start: StartReference, commands: np.ndarray, sensors: np.ndarray,
                time_s: np.ndarray, sensor_names: Sequence[str], dt_s: float,
                outing: str = "dive") -> StartCheck:
    """``outing``: what one log of the vehicle is called ("dive", "flight")."""
    def not_judged(why: str) -> StartCheck:
        return StartCheck(False, why, {}, {}, (), None)

    # The log's own reason first: a log under way is not judged whatever the model holds.
    reading = start_reading(commands, sensors, dt_s)
    if reading is None:
        return not_judged("the log is not recorded from rest: its commands already act on "
                          f"its first complete step, so it may begin mid-{outing}")
    if not start.usable:
        return not_judged(start.refused or "the model has no start state: train learns it")
    deviation = reading.sensors - np.asarray(start.reference)
    thresholds = np.asarray([np.nan if t is None else t for t in start.thresholds], float)
    if np.isnan(thresholds).all():
        return not_judged("the normal logs' starts spread too much for any sensor")
    off = tuple(name for i, name in enumerate(sensor_names)
                if np.isfinite(deviation[i]) and abs(deviation[i]) > thresholds[i])
    first = int(np.flatnonzero(np.isfinite(sensors).all(axis=1))[0])
    end = min(len(time_s) - 1, first + max(1, round(SPAN_S / dt_s)) - 1)
    return StartCheck(True, None, {n: round(float(d), 6) for n, d in zip(
        sensor_names, deviation, strict=True)}, {n: float(t) for n, t in zip(
            sensor_names, thresholds, strict=True) if np.isfinite(t)}, off,
        round(float(time_s[end]), 3))
