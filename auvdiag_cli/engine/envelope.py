"""How far the logs a model learnt from took the vehicle, and a finding that comes after
the vehicle went past that: a learnt model extrapolates there, and its error there is no
evidence of a fault.

The model keeps each signal's largest |value| over the logs it learnt from (its envelope).
A fault the tool finds in a log where, in the stretch before the fault's estimated onset, a
signal the replay judges went past MARGIN times that, is not a finding the model can make:
the verdict is undetermined, and the report says how far past it went. What a fault does to
the vehicle comes after its onset (a motor lost spins a quadrotor up), so it does not count,
unless the signal was already past what was learnt at the onset and went on past MARGIN
times it by the detection: the model's error began to grow as the vehicle left what it
learnt. On the simulated BlueROV2 trained on three slow missions, its sprints (surge to 2.7
times the fastest it learnt from, from 6-7 s) alarmed 8-13 s later; no fault of its mission
scenarios took a judged signal past 1.09 times it before the onset. Calibrated on those
three missions, a lower surge threshold dated one sprint's alarm at 6.1 s, its surge 1.22
times the fastest learnt and past it since 5 s: the second rule takes it."""

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.results import Finding, Verdict

MARGIN = 1.25
PAST_ENVELOPE = "the vehicle went past what the model learnt from"
# How long before the estimated onset a signal past the envelope makes the finding the
# model's extrapolation: the replay's error builds up over seconds after it went past.
LOOKBACK_S = 10.0


@dataclass(frozen=True)
class Beyond:
    """A signal past the envelope before a finding's onset."""

    signal: str
    since_s: float          # when it first went past MARGIN x the envelope in the stretch
    reached: float          # the largest |value| it reached there
    learnt: float           # the largest |value| the model learnt from

    def describe(self) -> str:
        return (f"{self.signal} reached {self.reached:.3g} from {self.since_s:.1f} s, past "
                f"the {self.learnt:.3g} it reached at most in the logs the model learnt "
                f"from: the model extrapolates there, and its error there is no evidence "
                f"of a fault")


def envelope_entry(sensors: list[np.ndarray], names: tuple[str, ...]) -> dict[str, Any]:
    """model.json's `envelope`: per signal, the largest |value| over ``sensors`` (each a
    log's steps x signals, the steps it learnt from)."""
    stacked = np.vstack([np.empty((0, len(names))), *sensors])
    largest = np.nanmax(np.abs(stacked), axis=0, initial=0.0)
    return {"margin": MARGIN, "sensors": {name: round(float(v), 9)
                                          for name, v in zip(names, largest, strict=True)
                                          if np.isfinite(v) and v > 0}}


def beyond_before(envelope: dict[str, float], judged: list[str], names: tuple[str, ...],
                  time_s: np.ndarray, sensors: np.ndarray, onset_s: float,
                  detected_s: float | None = None) -> Beyond | None:
    """The judged signal that went furthest past the envelope within LOOKBACK_S before
    ``onset_s``, or (`_past_from_onset`) that was past what was learnt at the onset and
    went on past MARGIN times it by ``detected_s`` (None: none did)."""
    stretch = (time_s >= onset_s - LOOKBACK_S) & (time_s <= onset_s)
    found: Beyond | None = None
    for name in judged:
        learnt = envelope.get(name)
        if not learnt:
            continue
        values = np.nan_to_num(np.abs(sensors[:, names.index(name)]))
        past = np.flatnonzero(stretch & (values > MARGIN * learnt))
        span = (past[0], values[stretch]) if past.size else _past_from_onset(
            values, time_s, onset_s, detected_s, learnt)
        if span is not None and (found is None or float(span[1].max()) / learnt
                                 > found.reached / found.learnt):
            found = Beyond(name, float(time_s[span[0]]), float(span[1].max()), learnt)
    return found


def _past_from_onset(values: np.ndarray, time_s: np.ndarray, onset_s: float,
                     detected_s: float | None, learnt: float
                     ) -> tuple[int, np.ndarray] | None:
    """Where ``values`` are past ``learnt`` at the onset and, staying past it, go past MARGIN
    times it by ``detected_s``: the step they first do, and the values from the onset for
    as long as they stay past it. The vehicle was already beyond what the model learnt from
    when its error began to grow (a sprint accelerating past the fastest mission learnt),
    which a fault, whose effect begins at its onset within the learnt range, does not
    explain (None: not so)."""
    if detected_s is None:
        return None
    start = int(np.searchsorted(time_s, onset_s))
    span = values[start:int(np.searchsorted(time_s, detected_s, side="right"))]
    if not span.size or span[0] <= learnt:
        return None
    beyond = span > learnt
    span = span if beyond.all() else span[:int(np.argmin(beyond))]
    over = np.flatnonzero(span > MARGIN * learnt)
    return (start + int(over[0]), span) if over.size else None


def within_the_envelope(finding: Finding, normal: Finding, envelope: dict[str, float],
                        judged: list[str], frame: AlignedFrame) -> Finding:
    """``finding``, or where it is a fault after a ``judged`` signal went past the
    ``envelope`` (`beyond_before` its onset), undetermined (``normal``'s notes), saying what
    the alarm would have named and how far past the envelope the vehicle went."""
    if finding.verdict is not Verdict.FAULT or finding.onset_s is None:
        return finding
    beyond = beyond_before(envelope, judged, frame.sensor_names, frame.time_s, frame.sensors,
                           finding.onset_s, finding.detected_at_s)
    if beyond is None:
        return finding
    named = finding.component or " or ".join(finding.candidates) or "no single component"
    when = "" if finding.detected_at_s is None else f" at {finding.detected_at_s:.1f} s"
    return replace(normal, verdict=Verdict.UNDETERMINED, case=None,
                   undetermined_because=PAST_ENVELOPE).noted(
        f"an alarm{when} (it named {named}) is not taken for a fault: {beyond.describe()}; "
        "train the model on normal logs that go as far")
