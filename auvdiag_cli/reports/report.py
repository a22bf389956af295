"""The diagnosis report, typed: what the JSON report holds (SPEC §5; docs/reports.md names
every key), built once from a `Diagnosis` (`reports.report_build`) or read back from a
saved JSON report, and what the terminal summary, the PDF, the MCAP export and the audit
read. Each field is named as its JSON key, in the JSON's order (`report_codec`); a key an
older report lacks takes its field's default."""

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from auvdiag_cli.engine.coverage import Coverage
from auvdiag_cli.reports.report_codec import from_plain, to_plain

SCHEMA_VERSION = 1
Numbers = Mapping[str, float | None]


@dataclass(frozen=True, kw_only=True)
class CompletenessPart:
    status: str                       # "complete" or "partial"
    bytes_total: int | None = None
    bytes_read: int | None = None
    messages_read: int | None = None
    seconds_read: float | None = None
    damage_at_byte: int | None = None
    reason: str | None = None


@dataclass(frozen=True, kw_only=True)
class JudgedPart:
    judged: tuple[str, ...] = ()
    not_judged: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class CoveragePart:
    summary: str
    complete: bool = True
    signals: JudgedPart = field(default_factory=JudgedPart)
    actuators: JudgedPart = field(default_factory=JudgedPart)
    start_judged: bool = False
    judged_from_s: float | None = None

    def engine(self) -> Coverage:
        """The engine's coverage, which says it in words."""
        return Coverage((*self.signals.judged, *self.signals.not_judged), self.signals.judged,
                        (*self.actuators.judged, *self.actuators.not_judged),
                        self.actuators.judged, self.start_judged, self.judged_from_s)


@dataclass(frozen=True, kw_only=True)
class SegmentPart:
    name: str
    start_s: float
    end_s: float
    mode: str                         # "mission" or "routine"
    thresholds: Numbers = field(default_factory=dict)
    max_g: Numbers = field(default_factory=dict)
    b: Mapping[str, int] = field(default_factory=dict)
    case: int | None = None
    components: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class DegradationPart:
    component: str
    kind: str = "weakened"
    thrust_fraction: float | None = None
    peak_g_over_threshold: float | None = None


@dataclass(frozen=True, kw_only=True)
class HypothesisPart:
    component: str
    kind: str
    description: str | None = None    # reports before it: rebuilt from kind and fraction
    thrust_fraction: float | None = None
    stuck_at: str | None = None
    peak_g_over_threshold: float | None = None
    explains: bool = False
    ruled_out: str | None = None      # why it was not replayed


@dataclass(frozen=True, kw_only=True)
class HypothesesPart:
    best: HypothesisPart
    runner_up: HypothesisPart | None = None
    margin: float | None = None
    table_agrees: bool | None = None
    ranked: tuple[HypothesisPart, ...] = ()


@dataclass(frozen=True, kw_only=True)
class CommandsPart:
    summary: str
    window_s: float | None = None
    extra_effort_allowed: Numbers = field(default_factory=dict)
    peak_over_threshold: Numbers = field(default_factory=dict)
    not_judged: Mapping[str, str] = field(default_factory=dict)
    alarm_s: float | None = None
    onset_s: float | None = None
    onset_error_s: float | None = None      # null: the start of the first window over
    named: tuple[str, ...] = ()
    explained: Numbers | None = None
    extra_effort: float | None = None
    # What the two effort figures measure: "extra effort" (command beyond what the motion
    # needs) or "thrust lost" (share of the thrust the motion did not show).
    measure: str = "extra effort"


@dataclass(frozen=True, kw_only=True)
class StartPart:
    summary: str
    judged: bool = False
    deviation: Numbers = field(default_factory=dict)
    allowed: Numbers = field(default_factory=dict)
    off: tuple[str, ...] = ()
    at_s: float | None = None


@dataclass(frozen=True, kw_only=True)
class ChangePart:
    summary: str
    judged: bool = False
    judged_from_s: float | None = None
    thresholds: Mapping[str, Numbers] = field(default_factory=dict)
    peaks: Mapping[str, Numbers] = field(default_factory=dict)
    alarm_s: float | None = None
    onset_s: float | None = None
    onset_error_s: float | None = None
    # The change's sum ran from the first step judged: it may lie in the reference.
    onset_in_reference: bool = False
    flagged: Numbers = field(default_factory=dict)
    carried: Numbers = field(default_factory=dict)
    # Each flagged signal -> the way it moved from the onset ("above", "below" the prediction).
    ways: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class SignaturePart:
    actuator: str
    match: float


@dataclass(frozen=True, kw_only=True)
class SharePart:
    group: str
    component: str
    share: float | None = None
    normal_share: float | None = None
    spread: float | None = None
    departure: float | None = None
    over_threshold: float | None = None
    driven_harder: bool = False
    judged: bool = False
    not_judged: str | None = None
    # The smallest rise of its share (0.08: 8 % more) that shows over this log against the
    # normal logs: with few normal logs, a weakness must be large to stand out.
    smallest_rise_shown: float | None = None
    # Where its group changed within the log: its share since the onset against before it,
    # less one (0.6: 60 % more); null otherwise.
    since_onset: float | None = None


@dataclass(frozen=True, kw_only=True)
class ActuatorsPart:
    summary: str
    judged: bool = False
    false_alarm_rate: float | None = None
    alarm_s: float | None = None
    onset_s: float | None = None
    onset_error_s: float | None = None      # null: the whole log departs, from its start
    # The alarm is the whole log against normal logs that differ no more than their noise.
    against_alike_logs: bool = False
    named: tuple[str, ...] = ()
    # The components named in the suspect's group are ones its shares cannot tell apart.
    cannot_tell_apart: bool = False
    signatures: tuple[SignaturePart, ...] = ()
    shares: Mapping[str, SharePart] = field(default_factory=dict)
    # Where none alarmed, the component the few normal logs cannot rule out weak, and how
    # many normal logs like them would judge it (null: more than the tool says).
    not_ruled_out: str | None = None
    not_ruled_out_judged_with_logs: int | None = None


@dataclass(frozen=True, kw_only=True)
class EvidencePart:
    log: str
    segment: str
    start_s: float
    b: Mapping[str, int] = field(default_factory=dict)
    tested: tuple[str, ...] = ()
    faulty: bool = False


@dataclass(frozen=True, kw_only=True)
class ActivePart:
    candidates_before: tuple[str, ...] = ()
    candidates_after: tuple[str, ...] = ()
    evidence: tuple[EvidencePart, ...] = ()
    recommended_dms: tuple[str, ...] = ()
    conflict: bool = False


@dataclass(frozen=True, kw_only=True)
class ClosedLoopPart:
    from_s: float
    reached_last_waypoint: bool
    finished_s: float | None = None
    miss_m: float | None = None
    last_waypoint_m: tuple[float, ...] = ()
    end_m: tuple[float, ...] = ()


@dataclass(frozen=True, kw_only=True)
class SubstitutionPart:
    signal: str
    from_s: float
    unit: str = ""
    expected_error_rms: float | None = None
    truth_error_rms: float | None = None
    failed_sensor_error_rms: float | None = None
    track_end_m: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    track_end_error_m: Numbers = field(default_factory=dict)
    closed_loop: ClosedLoopPart | None = None


@dataclass(frozen=True, kw_only=True)
class BudgetPart:
    rate: float
    per: str                          # "log" or "hour"


@dataclass(frozen=True, kw_only=True)
class ModelPart:
    name: str | None = None
    vehicle: str | None = None
    path: str | None = None
    weights_sha256: str | None = None
    created: str | None = None
    heldout_error_rms: Numbers | None = None
    horizon_s: float | None = None
    skill: Numbers | None = None
    predictors: Mapping[str, str] = field(default_factory=dict)
    inputs: tuple[str, ...] = ()
    thresholds_calibrated: bool = False
    false_alarm_rate: BudgetPart | None = None


@dataclass(frozen=True, kw_only=True)
class MethodPart:
    g: str = ""
    window_samples: int | None = None
    decision_window_s: float | None = None
    assumptions: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class AlarmPart:
    """A text of trouble the vehicle's own software wrote, as often as it repeated it."""

    text: str
    severity: int | None = None        # MAV_SEVERITY, 0 emergency … 4 warning; None: unsaid
    first_s: float
    last_s: float
    times: int = 1


@dataclass(frozen=True, kw_only=True)
class AutopilotPart:
    """What the vehicle's own software said while it operated (null: the log keeps none)."""

    summary: str
    alarms: tuple[AlarmPart, ...] = ()
    other_messages: int = 0
    standing: tuple[AlarmPart, ...] = ()     # statuses already wrong when the log began


@dataclass(frozen=True, kw_only=True)
class Report:
    schema_version: int = SCHEMA_VERSION
    tool: str = ""
    log: str
    format: str = ""
    vehicle: str = ""
    verdict: str                      # "fault", "normal" or "undetermined"
    undetermined_because: str | None = None   # None: no signal could be judged
    component: str | None = None
    candidates: tuple[str, ...] = ()
    case: int | None = None
    b: Mapping[str, int] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    detected_at_s: float | None = None
    onset_s: float | None = None
    onset_error_s: float | None = None      # null: the judge that dated it states none
    duration_s: float | None = None
    start_time_utc: str | None = None
    onset_utc: str | None = None
    detected_at_utc: str | None = None
    completeness: CompletenessPart | None = None
    not_operating_s: float | None = None
    not_judged: Mapping[str, str] = field(default_factory=dict)
    coverage: CoveragePart | None = None
    segments: tuple[SegmentPart, ...] = ()
    segment_source: str | None = None
    degradation: DegradationPart | None = None
    hypotheses: HypothesesPart | None = None
    commands_check: CommandsPart | None = None
    start_check: StartPart | None = None
    change_check: ChangePart | None = None
    actuators: ActuatorsPart | None = None
    active_diagnosis: ActivePart | None = None
    substitution: SubstitutionPart | None = None
    autopilot: AutopilotPart | None = None
    model: ModelPart = field(default_factory=ModelPart)
    method: MethodPart = field(default_factory=MethodPart)
    notes: tuple[str, ...] = ()

    @property
    def named(self) -> str:
        """What the report blames, in words: its component, or its candidates joined by
        "or" ("" when it names none)."""
        return self.component or " or ".join(self.candidates)

    @property
    def partial(self) -> bool:
        """Analysed only up to damage."""
        return self.completeness is not None and self.completeness.status == "partial"

    def to_json(self) -> dict[str, object]:
        """The JSON report, as json.dumps writes it."""
        plain = to_plain(self)
        assert isinstance(plain, dict)
        return plain

    @classmethod
    def from_json(cls, document: Mapping[str, object]) -> "Report":
        """A report from its JSON (keys it does not name, such as an audit's stamp, are
        left aside). ValueError where it is not a report."""
        return from_plain(cls, document)

    @classmethod
    def read(cls, path: Path) -> "Report":
        """A saved JSON report; ValueError (or OSError) where it cannot be read as one."""
        return cls.from_json(json.loads(path.read_text(encoding="utf-8")))
