"""Which single-component fault explains the log: the paper's pattern table, generalised.

From the estimated onset on, the log is replayed under every single-component fault the
profile's components admit, and each hypothesis is scored by the largest g / threshold it
leaves after the onset (on the judged signals, from one window after the onset, when g
covers only faulty time). Below 1 the hypothesis *explains* the log: with that fault
assumed, no signal would have alarmed.

- an actuator (the commands of one component) dead, or giving a fraction of its thrust:
  the commands are replayed scaled from the onset (thrust grows as command·|command|, so a
  fraction f of thrust is sqrt(f) of the command);
- a sensor (the signals of one component) dead (reads 0), stuck (at its value just before
  the onset), biased (a constant offset from the model, fitted) or drifting (an offset
  growing linearly from the onset, fitted).

This is also what goes beyond the paper's assumption 3 (a component is normal or totally
defective): a thruster that lost part of its power can look like a sensor fault to the
pattern table (at 50 % the yaw residual grows first), and a thruster that dies in a turn can
raise the yaw bit alone at first; the weakened or dead thruster's replay explains such a
log where the table's sensor cannot.
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.residuals import Matching, match_trials
from auvdiag_cli.numeric import peak
from auvdiag_cli.vehicle.actuators import SET_POINT
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

THRUST_FRACTIONS = (0.0, 0.25, 0.5, 0.75)
SENSOR_FAULTS = ("dead", "stuck", "biased", "drifting")
STUCK_FROM_SAMPLES = 5       # a stuck sensor's value: the median of the samples before onset


@dataclass(frozen=True)
class Hypothesis:
    component: str
    kind: str                            # dead, weakened, stuck, biased, drifting
    peak_g_ratio: float                  # largest g / threshold after the onset, assumed
    thrust_fraction: float | None = None  # actuators: 0 dead, else weakened to this

    @property
    def explains(self) -> bool:
        return self.peak_g_ratio < 1.0

    @property
    def is_actuator(self) -> bool:
        return self.thrust_fraction is not None

    def describe(self) -> str:
        name = self.component.replace("_", " ")
        if self.kind == "weakened":
            return f"{name} weakened to {self.thrust_fraction:.0%} thrust"
        return f"{name} {self.kind}"


@dataclass(frozen=True)
class HypothesisTest:
    ranked: tuple[Hypothesis, ...]       # best first

    @property
    def best(self) -> Hypothesis:
        return self.ranked[0]

    @property
    def runner_up(self) -> Hypothesis | None:
        """The best hypothesis about another component."""
        return next((h for h in self.ranked if h.component != self.best.component), None)

    @property
    def margin(self) -> float | None:
        """How many times more of its threshold the runner-up leaves than the best."""
        other = self.runner_up
        if other is None or self.best.peak_g_ratio <= 0:
            return None
        return other.peak_g_ratio / self.best.peak_g_ratio


@dataclass(frozen=True)
class _Judge:
    """What scoring a hypothesis needs: where g counts, against what."""

    measured: np.ndarray
    thresholds: np.ndarray
    judging: Judging
    onset: int

    def ratio(self, g_after_onset: np.ndarray) -> float:
        """Infinite where g never covers faulty time (the log ends too soon after the
        onset): nothing is explained then."""
        start = min(self.judging.window, max(0, len(g_after_onset) - 1))
        judged = self.judging.judged_mask
        g = g_after_onset[start:, judged]
        ratio = peak(g / self.thresholds[self.onset + start:, judged])
        return round(ratio, 3) if np.isfinite(ratio) else float("inf")

    def ratio_of(self, predicted: np.ndarray) -> float:
        after = slice(self.onset, None)
        return self.ratio(self.judging.g(self.measured[after], predicted[after]))


def weigh_hypotheses(model: LoadedModel, judging: Judging, frame: AlignedFrame,
                    matching: Matching, thresholds: np.ndarray, onset: int,
                    restarts: Sequence[int]) -> HypothesisTest:
    judge = _Judge(matching.measured, thresholds, judging, onset)
    hypotheses = [*_actuator_hypotheses(model, judging.profile, frame, judge, restarts),
                  *_sensor_hypotheses(judging.profile, frame, matching, judge)]
    return HypothesisTest(tuple(sorted(hypotheses, key=lambda h: h.peak_g_ratio)))


def _actuator_hypotheses(model: LoadedModel, profile: Profile, frame: AlignedFrame,
                         judge: _Judge, restarts: Sequence[int]) -> list[Hypothesis]:
    # A set point drives the model but is no part that can weaken.
    components = dict.fromkeys(c.component for c in profile.commands if c.kind != SET_POINT)
    trials = [(component, fraction) for component in components
              for fraction in THRUST_FRACTIONS]
    if not trials:
        return []
    histories = []
    for component, fraction in trials:
        columns = [i for i, c in enumerate(profile.commands) if c.component == component]
        commands = frame.commands.copy()
        commands[judge.onset:, columns] *= np.sqrt(fraction)
        histories.append(commands)
    # Every trial replays the log from the onset, all of them together.
    matched = match_trials(model, frame, histories, judge.judging.full_scale,
                           judge.judging.window, restarts, since=judge.onset)
    return [Hypothesis(component, "dead" if fraction == 0 else "weakened",
                       judge.ratio(trial.g_percent[judge.onset:]), fraction)
            for (component, fraction), trial in zip(trials, matched, strict=True)]


def _sensor_hypotheses(profile: Profile, frame: AlignedFrame, matching: Matching,
                       judge: _Judge) -> list[Hypothesis]:
    found = []
    onset = judge.onset
    elapsed = frame.time_s[onset:] - frame.time_s[onset]
    for component in dict.fromkeys(s.component for s in profile.sensors):
        columns = [i for i, s in enumerate(profile.sensors) if s.component == component]
        for kind in SENSOR_FAULTS:
            predicted = matching.modelled.copy()
            for i in columns:
                predicted[onset:, i] = _faulty_reading(kind, matching.measured[:, i],
                                                       matching.modelled[:, i], onset, elapsed)
            found.append(Hypothesis(component, kind, judge.ratio_of(predicted)))
    return found


def _faulty_reading(kind: str, measured: np.ndarray, modelled: np.ndarray, onset: int,
                    elapsed: np.ndarray) -> np.ndarray:
    """What the sensor would read from the onset on under ``kind``."""
    after = measured[onset:] - modelled[onset:]
    usable = np.isfinite(after)
    if kind == "dead":
        return np.zeros_like(elapsed)
    if kind == "stuck":
        before = measured[max(0, onset - STUCK_FROM_SAMPLES):onset + 1]
        before = before[np.isfinite(before)]
        return np.full_like(elapsed, float(np.median(before)) if before.size else 0.0)
    if not usable.any():
        return modelled[onset:]
    if kind == "biased":
        return modelled[onset:] + float(np.median(after[usable]))
    # drifting: the offset grows at the least-squares rate through zero at the onset
    weight = float((elapsed[usable] ** 2).sum())
    rate = float((after[usable] * elapsed[usable]).sum()) / weight if weight > 0 else 0.0
    return modelled[onset:] + rate * elapsed
