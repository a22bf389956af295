"""Which single-component fault explains the log: the paper's pattern table, generalised.

From the estimated onset on, the log is replayed under every single-component fault the
profile's components admit, and each hypothesis is scored by the largest g / threshold it
leaves after the onset (on the judged signals, from one window after the onset, when g
covers only faulty time). Below 1 the hypothesis *explains* the log: with that fault
assumed, no signal would have alarmed.

- a thruster, rotor or engine (the commands of one component) dead, or giving a fraction
  of its thrust: the commands are replayed scaled from the onset (thrust grows as
  command·|command|, so a fraction f of thrust is sqrt(f) of the command);
- a control surface stuck from the onset: at its trim (its median command before the
  onset), where it was (its command just before), or hard over (the least and the largest
  command before the onset): the commands are replayed held there;
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
from dataclasses import dataclass, replace

import numpy as np

from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.residuals import Matching, match_trials
from auvdiag_cli.engine.shares_rule_out import ruled_out_by_shares
from auvdiag_cli.numeric import peak
from auvdiag_cli.vehicle.actuators import CONTROL_SURFACE, SET_POINT
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

THRUST_FRACTIONS = (0.0, 0.25, 0.5, 0.75)
SENSOR_FAULTS = ("dead", "stuck", "biased", "drifting")
# Faults whose reading is fitted to the log after the onset (an offset, a rate): fitted
# there, they absorb whatever else moved that signal, a weak actuator's effect included.
FITTED_TO_THE_LOG = ("biased", "drifting")
STUCK_FROM_SAMPLES = 5       # a stuck part's value: the median of the samples before onset
# A sensor dead or stuck reads one value from the onset on: one whose every signal changes
# after the onset at this share, at least, of the steps it changed at before is neither (an
# onset dated a little early leaves a dead one's few last readings after it). A closed loop
# holds its rates near zero, so "the gyro reads 0" fitted a simulated quadrotor's log better
# than the rotor weakened there while the gyro kept reading its noise.
STILL_MOVING = 0.5
ONE_VALUE = ("dead", "stuck")
KEPT_MOVING = "its signals kept changing after the onset as often as before it"
TRIM, WHERE_IT_WAS, LOW_LIMIT, HIGH_LIMIT = ("at its trim", "where it was",
                                             "hard over at its least command",
                                             "hard over at its largest command")


@dataclass(frozen=True)
class Hypothesis:
    component: str
    kind: str                            # dead, weakened, stuck, biased, drifting
    peak_g_ratio: float                  # largest g / threshold after the onset, assumed
    thrust_fraction: float | None = None  # pushing parts: 0 dead, else weakened to this
    part: str | None = None              # an actuator's kind (`vehicle.actuators`); None: a sensor
    stuck_at: str | None = None          # a control surface's: where it stuck
    ruled_out: str | None = None         # why it was not replayed (peak_g_ratio inf)

    @property
    def explains(self) -> bool:
        return self.peak_g_ratio < 1.0

    @property
    def is_actuator(self) -> bool:
        return self.part is not None

    @property
    def fitted(self) -> bool:
        """A sensor fault fitted to the log after the onset (`FITTED_TO_THE_LOG`)."""
        return not self.is_actuator and self.kind in FITTED_TO_THE_LOG

    def describe(self) -> str:
        name = self.component.replace("_", " ")
        if self.stuck_at is not None:
            return f"{name} stuck {self.stuck_at}"
        if self.part == "engine" and self.thrust_fraction is not None:
            return (f"{name} lost its thrust" if self.thrust_fraction == 0
                    else f"{name} at {self.thrust_fraction:.0%} of its thrust")
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


def weigh_hypotheses(judging: Judging, frame: AlignedFrame, matching: Matching,
                     thresholds: np.ndarray, onset: int, restarts: Sequence[int],
                     effort: EffortCheck | None = None) -> HypothesisTest:
    """Every single-component fault from ``onset``, best first; a weakness the ``effort``
    shares rule out (`shares_rule_out`) stays, ruled out."""
    judge = _Judge(matching.measured, thresholds, judging, onset)
    actuators = [_unless_the_shares_rule_out(h, effort, float(frame.time_s[onset]))
                 for h in _actuator_hypotheses(judging.model, judging.profile, frame, judge,
                                               restarts)]
    hypotheses = [*actuators, *_sensor_hypotheses(judging.profile, frame, matching, judge)]
    return HypothesisTest(tuple(sorted(hypotheses, key=lambda h: h.peak_g_ratio)))


def _unless_the_shares_rule_out(hypothesis: Hypothesis, effort: EffortCheck | None,
                                onset_s: float) -> Hypothesis:
    fraction = hypothesis.thrust_fraction
    why = None if fraction is None else ruled_out_by_shares(
        effort, hypothesis.component, fraction, onset_s, hypothesis.describe())
    return hypothesis if why is None else replace(hypothesis, peak_g_ratio=float("inf"),
                                                  ruled_out=why)


def _actuator_hypotheses(model: LoadedModel, profile: Profile, frame: AlignedFrame,
                         judge: _Judge, restarts: Sequence[int]) -> list[Hypothesis]:
    # A set point drives the model but is no part that can fail.
    parts = {c.component: c.kind for c in profile.commands if c.kind != SET_POINT}
    trials: list[tuple[Hypothesis, np.ndarray]] = []
    for component, part in parts.items():
        columns = [i for i, c in enumerate(profile.commands) if c.component == component]
        trials += (_stuck_surfaces if part == CONTROL_SURFACE else _weakened)(
            component, part, columns, frame.commands, judge.onset)
    if not trials:
        return []
    # Every trial replays the log from the onset, all of them together.
    matched = match_trials(model, frame, [commands for _, commands in trials],
                           judge.judging.full_scale, judge.judging.window, restarts,
                           since=judge.onset)
    return [replace(hypothesis, peak_g_ratio=judge.ratio(trial.g_percent[judge.onset:]))
            for (hypothesis, _), trial in zip(trials, matched, strict=True)]


def _weakened(component: str, part: str, columns: list[int], commands: np.ndarray,
              onset: int) -> list[tuple[Hypothesis, np.ndarray]]:
    """A part that pushes, dead or giving a fraction of its thrust from the onset."""
    trials = []
    for fraction in THRUST_FRACTIONS:
        trial = commands.copy()
        trial[onset:, columns] *= np.sqrt(fraction)
        trials.append((Hypothesis(component, "dead" if fraction == 0 else "weakened",
                                  float("inf"), fraction, part), trial))
    return trials


def _stuck_surfaces(component: str, part: str, columns: list[int], commands: np.ndarray,
                    onset: int) -> list[tuple[Hypothesis, np.ndarray]]:
    """A control surface held from the onset where it may have stuck (none where nothing
    before the onset says where that is)."""
    before = commands[:onset, columns]
    known = np.isfinite(before).all(axis=1)
    if not known.any():
        return []
    before = before[known]
    positions = {TRIM: np.median(before, axis=0),
                 WHERE_IT_WAS: np.median(before[-STUCK_FROM_SAMPLES:], axis=0),
                 LOW_LIMIT: before.min(axis=0), HIGH_LIMIT: before.max(axis=0)}
    trials = []
    for where, held in positions.items():
        trial = commands.copy()
        trial[onset:, columns] = held
        trials.append((Hypothesis(component, "stuck", float("inf"), part=part, stuck_at=where),
                       trial))
    return trials


def _sensor_hypotheses(profile: Profile, frame: AlignedFrame, matching: Matching,
                       judge: _Judge) -> list[Hypothesis]:
    found = []
    onset = judge.onset
    elapsed = frame.time_s[onset:] - frame.time_s[onset]
    for component in dict.fromkeys(s.component for s in profile.sensors):
        columns = [i for i, s in enumerate(profile.sensors) if s.component == component]
        moving = all(still_moving(matching.measured[:, i], onset) for i in columns)
        for kind in SENSOR_FAULTS:
            if moving and kind in ONE_VALUE:
                found.append(Hypothesis(component, kind, float("inf"), ruled_out=KEPT_MOVING))
                continue
            predicted = matching.modelled.copy()
            for i in columns:
                predicted[onset:, i] = _faulty_reading(kind, matching.measured[:, i],
                                                       matching.modelled[:, i], onset, elapsed)
            found.append(Hypothesis(component, kind, judge.ratio_of(predicted)))
    return found


def still_moving(measured: np.ndarray, onset: int) -> bool:
    """Whether a signal's reading changes after ``onset`` about as often as before it
    (`STILL_MOVING`)."""
    def changing(values: np.ndarray) -> float:
        values = values[np.isfinite(values)]
        return float(np.mean(np.diff(values) != 0)) if len(values) > 1 else 0.0

    before = changing(measured[:onset])
    return before > 0 and changing(measured[onset:]) >= STILL_MOVING * before


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
