"""What a diagnosis is: the verdict, the component, the evidence beside them and the time
histories the reports draw. Rendering reads these values and never recomputes them."""

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from datetime import UTC, datetime
from enum import StrEnum
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.active import ActiveDiagnosis, DmsRun
from auvdiag_cli.engine.autopilot_words import AutopilotSaid
from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.change_columns import judged_by
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.completeness import Completeness
from auvdiag_cli.engine.coverage import Coverage, coverage_of
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.missions import MissionLeg
from auvdiag_cli.engine.segments import ROUTINE_MODE, Segment
from auvdiag_cli.engine.start_check import StartCheck
from auvdiag_cli.engine.substitution import Substitution
from models.card import ModelIdentity

EPOCH_CLOCK_NS = 10**17     # larger times are Unix time; smaller ones count from boot


def utc_day(time_ns: int) -> str | None:
    """The UTC day (ISO date) of a time on a log's clock; None on a clock since boot."""
    if time_ns <= EPOCH_CLOCK_NS:
        return None
    return datetime.fromtimestamp(time_ns / 1e9, UTC).date().isoformat()

PAPER_ASSUMPTIONS = (
    "The environment is steady: a change in how the vehicle moves comes only from its hardware.",
    "At most one sensor or actuator is defective at a time.",
    "A component is either normal or totally defective.",
    "Once defective, a component stays defective until the diagnosis ends.",
)


class Verdict(StrEnum):
    """What a diagnosis concludes; the value is what the reports write."""

    NORMAL = "normal"                  # something was judged and nothing failed
    FAULT = "fault"
    UNDETERMINED = "undetermined"      # nothing could be judged


@dataclass(frozen=True)
class SegmentResult:
    segment: Segment
    max_g: Mapping[str, float]
    b: Mapping[str, int]
    case: int | None
    components: tuple[str, ...]


@dataclass(frozen=True, kw_only=True)
class Observations:
    """What a diagnosis measured before concluding anything: the log, the replay's
    histories and the checks beside it."""

    log: Path
    format: str
    vehicle: str
    segments: tuple[SegmentResult, ...]
    segment_source: str               # "markers" or "commands"
    model: ModelIdentity
    window_samples: int
    decision_window_s: float
    sensor_units: Mapping[str, str]   # every sensor's, and each command's the profile gives
    start_ns: int = 0
    # The UTC time the log carries less its clock, where that is off (`engine.log_clock`).
    utc_offset_ns: int = 0
    mission_legs: tuple[MissionLeg, ...] = ()
    histories: Histories = field(default_factory=Histories)
    completeness: Completeness | None = None
    not_operating_s: float = 0.0      # time the operating flag excluded from judgement
    not_judged: Mapping[str, str] = field(default_factory=dict)   # signal -> why not
    set_aside: tuple[str, ...] = ()   # of those, what no judge takes in this log (flat)
    command_check: CommandCheck | None = None   # the commands judged against the motion
    start_check: StartCheck | None = None       # the log's start against normal starts
    effort_check: EffortCheck | None = None     # each actuator's share of its group's effort
    change_check: ChangeCheck | None = None     # the log against its own beginning
    set_points: tuple[str, ...] = ()            # commands that are set points, no actuator
    autopilot: AutopilotSaid | None = None      # what the vehicle's own software said


@dataclass(frozen=True, kw_only=True)
class Finding:
    """What the evidence concludes; each stage of isolation returns a new one."""

    verdict: Verdict
    b: Mapping[str, int]
    component: str | None = None
    candidates: tuple[str, ...] = ()
    case: int | None = None
    detected_at_s: float | None = None
    onset_s: float | None = None
    substitution: Substitution | None = None
    # The model of the healthy vehicle replayed from the change test's onset, per step and
    # sensor (`failure_effect.healthy_from_onset`): what the vehicle would have done.
    healthy_from_onset: np.ndarray | None = field(default=None, compare=False, repr=False)
    active: ActiveDiagnosis | None = None
    degradation: Hypothesis | None = None      # a thruster weakened (kind "weakened")
    hypotheses: HypothesisTest | None = None
    notes: tuple[str, ...] = ()
    # Why the verdict is undetermined where it is (None: nothing could be judged).
    undetermined_because: str | None = None
    # How far the onset may lie from onset_s, as the judge that dated it states (None: it
    # states none: the replay's window, a window's start): `onset_dating`.
    onset_error_s: float | None = None

    def noted(self, *notes: str) -> "Finding":
        return replace(self, notes=(*self.notes, *notes))


@dataclass(frozen=True, kw_only=True)
class Diagnosis(Observations, Finding):
    """One log's diagnosis: its observations and its finding, built once."""

    @classmethod
    def of(cls, observed: Observations, finding: Finding) -> "Diagnosis":
        return cls(**{f.name: getattr(observed, f.name) for f in fields(Observations)},
                   **{f.name: getattr(finding, f.name) for f in fields(Finding)})

    @property
    def judged_g(self) -> np.ndarray:
        """g per step and signal, NaN for a signal this log set aside (a sensor it never
        fed: its g says nothing of the model)."""
        histories = self.histories
        assert histories.matching is not None
        g = histories.matching.g_percent.copy()
        g[:, [histories.sensor_names.index(name) for name in self.set_aside]] = np.nan
        return g

    @property
    def coverage(self) -> Coverage:
        """What the verdict looked at: signals (by the replay or against the log's own
        beginning), actuators, the start."""
        actuators = [c for c in self.histories.command_names if c not in self.set_points]
        change = self.change_check
        signals = self.histories.sensor_names or tuple(self.b)
        by_change = judged_by(change)
        # Where the change test alone judges the signals, it does so from a time on.
        since = (change.judged_from_s if change is not None and by_change
                 and all(n in self.not_judged for n in signals) else None)
        return coverage_of(signals, [n for n in self.not_judged if n not in by_change],
                           actuators, self.command_check, self.effort_check, self.start_check,
                           since)


def dms_runs(diagnosis: Observations) -> list[DmsRun]:
    """The log's DMS segments with their outcome, in absolute time."""
    return [DmsRun(str(diagnosis.log), r.segment.name,
                   diagnosis.start_ns + round(r.segment.start_s * 1e9),
                   diagnosis.start_ns + round(r.segment.end_s * 1e9), r.b)
            for r in diagnosis.segments if r.segment.mode == ROUTINE_MODE]
