"""The uniform signal frame every adapter produces.

Contract: each signal is a `Series`: float64 values at receive times in integer
nanoseconds (int64, the log's own clock), values in the profile's SI units, in the order the
log stored them (not yet sorted or de-duplicated: resampling does that, and reports what it
found). Plain NumPy arrays: reading a log needs no data-frame library. ``start_ns`` is the
time of the log's first message on any topic; report times are seconds from it.
"""

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from adapters.namespace import normalised, under
from adapters.recognise import is_number


@dataclass(frozen=True)
class FieldSource:
    """Where one signal lives in a log: a topic (ROS, MCAP) or message name (MAVLink,
    DataFlash), a field path, a linear map to SI units (value · scale + offset), and
    optionally fields a message must match to count (e.g. NAMED_VALUE_FLOAT ``name``)."""

    topic: str
    field: str
    scale: float = 1.0
    offset: float = 0.0
    where: tuple[tuple[str, str], ...] = ()
    merge_instances: bool = False     # True: several sensor instances make one signal
    bits: int = 0                     # a flag field: 1 where value & bits, else 0
    changes_only: bool = False        # logged only when it changes (DataFlash ARM events)
    # Raw values that count and what each means: integers (DataFlash EV ids 10 (armed) -> 1
    # and 11 (disarmed) -> 0) or texts (a flight mode, MOOS's IVPHELM_STATE = DRIVE); other
    # values mean ``otherwise``, or are no sample where it is None. Neither: all, as numbers.
    values: tuple[tuple[int | str, float], ...] = ()
    otherwise: float | None = None
    # An attitude angle from a quaternion logged as four fields (w, x, y, z: PX4's q[0..3],
    # a ROS orientation's .w .x .y .z): ``angle`` roll, pitch or yaw (rad, Z-Y-X order, in
    # the quaternion's own frames); ``field`` is then its w.
    quaternion: tuple[str, ...] = ()
    angle: str = ""

    @property
    def paths(self) -> tuple[str, ...]:
        """Every field path its value is read from."""
        return self.quaternion or (self.field,)

    @property
    def said(self) -> str:
        """Its field, as a reader names it: ``roll of q[0] q[1] q[2] q[3]``."""
        return f"{self.angle} of {' '.join(self.quaternion)}" if self.angle else self.field

    @property
    def mapped(self) -> bool:
        """Raw values are looked up (`values`, `otherwise`), not scaled: texts are read."""
        return bool(self.values) or self.otherwise is not None

    def convert(self, raw: Any) -> Any:
        """Raw field values (an array, or a NumPy scalar) to the signal's units, or to 0/1
        for a flag."""
        # A damaged float can hold a signalling NaN: converting it sets the invalid flag.
        # The NaN itself is dropped (and counted) when the signal is resampled.
        with np.errstate(invalid="ignore"):
            if self.bits:
                return ((raw.astype(np.int64) & self.bits) != 0).astype(np.float64)
            if self.mapped:
                return self._mapped(np.asarray(raw))
            return raw.astype(np.float64) * self.scale + self.offset

    def _mapped(self, raw: np.ndarray) -> np.ndarray:
        """``values`` applied, ``otherwise`` (NaN: no sample) for a value it does not list.
        A text key matches a text as written; an integer key a number, or a text that reads
        as that number ("10" in a CSV cell). A missing number (NaN) stays no sample."""
        texts: np.ndarray | None = None
        if raw.dtype.kind in "OSU":
            texts = np.array([as_text(v) for v in raw.ravel().tolist()], object)
            texts = texts.reshape(raw.shape)
            raw = np.array([_number(text) for text in texts.ravel().tolist()]).reshape(raw.shape)
        numbers = raw.astype(np.float64)
        out = np.full(raw.shape, np.nan if self.otherwise is None else self.otherwise)
        for key, meaning in self.values:
            if isinstance(key, int):
                out[numbers == key] = meaning
            elif texts is not None:
                out[texts == key] = meaning
        if texts is None:
            out[np.isnan(numbers)] = np.nan
        return out


EULER_ANGLES = ("roll", "pitch", "yaw")


def euler_angle(angle: str, w: Any, x: Any, y: Any, z: Any) -> Any:
    """Roll, pitch or yaw (rad; Z-Y-X, as aircraft and vehicles state their attitude) of the
    unit quaternion (w, x, y, z); arrays or scalars. A quaternion not quite of unit length
    (float rounding, a logger's half precision) gives the same angles."""
    with np.errstate(invalid="ignore", over="ignore"):
        if angle == "roll":
            return np.arctan2(2 * (w * x + y * z), w * w - x * x - y * y + z * z)
        if angle == "pitch":
            norm = w * w + x * x + y * y + z * z
            return np.arcsin(np.clip(2 * (w * y - z * x) / norm, -1.0, 1.0))
        return np.arctan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z)


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return np.nan


def readable_column(column: np.ndarray, source: FieldSource) -> np.ndarray | None:
    """The column as ``source`` reads it: numbers; a mapped source's texts as they are; texts
    that all read as numbers as those numbers (a CSV column another signal reads through a
    `values` map comes as its texts); None where it holds no numbers."""
    if column.dtype.kind in "biuf" or source.mapped:
        return column
    cells = column.tolist()
    if column.dtype.kind != "O" or not all(isinstance(c, str) and is_number(c) for c in cells):
        return None
    return np.array([float(c) for c in cells], np.float64)


def as_text(value: Any) -> str:
    """One reading of a logged text: bytes decoded up to a NUL, padding stripped."""
    if isinstance(value, bytes):
        value = value.split(b"\0", 1)[0].decode("utf-8", "replace")
    return str(value).rstrip("\0").strip()


@dataclass(frozen=True)
class SegmentSource:
    """Where segment markers live: a text field whose value, after ``prefix``, is the label."""

    topic: str
    field: str = "data"
    prefix: str = ""


_Source = TypeVar("_Source", FieldSource, SegmentSource, "WordSource")

# The reserved signal that says when the vehicle is operating (armed, under way): where a
# profile names one, only that time is trained on and judged.
OPERATING = "operating"
# The reserved signal of a UTC time the log carries on messages its own clock stamps (a
# GPS time reference): where the log's clock is off, its UTC times are set by it.
CLOCK_REFERENCE = "clock_reference"
# A MOOS variable's posting, the field a profile reads where it names no key of it, the
# app that posted it (a `where` keeps one app's postings), and what pLogger's LogAuxSrc
# logs after the app's name (the helm's behaviour).
MOOS_VALUE, MOOS_SOURCE, MOOS_SOURCE_AUX = "value", "source", "source_aux"
# The key of a profile's `values` map that says what every value it does not list means.
OTHER_VALUES = "*"
# CSV logs have no topics: a column is both a signal's topic and its field.
TIME_UNITS = ("s", "ms", "us", "ns", "iso", "hhmmss")


@dataclass(frozen=True)
class TimeColumn:
    """Where a CSV log keeps its clock: a column, in seconds, milliseconds, microseconds or
    nanoseconds (since the epoch or since boot), ISO 8601 text, or ``HHMMSS`` (a clock with
    one-second resolution)."""

    column: str
    unit: str = "s"


def fallback_name(signal: str) -> str:
    return f"{signal} (fallback)"


@dataclass(frozen=True)
class WordSource:
    """A topic on which the vehicle's software logs texts (`adapters.ros_words`): the field
    paths of the text, of its level and of who said it."""

    topic: str
    text: str
    level: str
    node: str | None = None
    at_root: bool = False              # global (``/rosout``): never under a namespace
    # (level as logged, MAVLink severity or None); None: the level is MAVLink's severity.
    severities: tuple[tuple[int, int | None], ...] | None = None
    only_without: str | None = None    # read only where this topic gave no message
    # The array of statuses each message holds (diagnostic_msgs/DiagnosticArray `status`):
    # text, level and node are then paths within each status, and only a status that
    # worsens is news (None: one text a message).
    statuses: str | None = None


@dataclass(frozen=True)
class LogSources:
    """What an adapter must extract: one source per signal, plus the segment markers (and for
    CSV logs, the time column)."""

    signals: dict[str, FieldSource]
    segment: SegmentSource | None = None
    time: TimeColumn | None = None
    # Where a signal may live instead when its own source has no message in a log (older
    # ArduSub DataFlash logs keep arming in EV records, not ARM).
    fallbacks: dict[str, FieldSource] = field(default_factory=dict)
    # The ROS namespace the topics are under: None finds it from the log's topics, "" is
    # the root (`adapters.namespace`).
    namespace: str | None = None
    # Signals a log may lack (a profile's measured inputs, which the model can hold at their
    # typical value): no topic, column or message of theirs is no error.
    optional: frozenset[str] = frozenset()
    # What the vehicle's software said, read where the log holds it (ROS: `/rosout`).
    words: tuple[WordSource, ...] = ()
    # Sources tried on a log (a draft's): one whose field a message lacks, or holds no
    # number at, reads nothing there, where a profile's would be an error.
    tentative: bool = False

    @property
    def wanted(self) -> dict[str, FieldSource]:
        """Every source to read: the signals', and their fallbacks' under `fallback_name`."""
        return {**self.signals, **{fallback_name(n): s for n, s in self.fallbacks.items()
                                   if n in self.signals}}

    def moved_under(self, namespace: str) -> "LogSources":
        """These sources as a vehicle launched under the ROS ``namespace`` publishes them."""
        def moved(source: _Source) -> _Source:
            return replace(source, topic=under(normalised(namespace), source.topic))

        return replace(self, signals={n: moved(s) for n, s in self.signals.items()},
                       fallbacks={n: moved(s) for n, s in self.fallbacks.items()},
                       segment=None if self.segment is None else moved(self.segment),
                       words=tuple(w if w.at_root else moved(w) for w in self.words))

    @property
    def topics(self) -> set[str]:
        """Every topic or message name the adapter has to read."""
        names = {src.topic for src in self.wanted.values()}
        return names | ({self.segment.topic} if self.segment else set())


@dataclass(frozen=True)
class SegmentMarker:
    """A label logged at the start of a diagnosis segment (``ZA``, ``ZB``, ``ZC``, ``MISSION``)."""

    time_ns: int
    label: str


@dataclass(frozen=True)
class Damage:
    """Where and why reading stopped short: the log was analysed up to here."""

    reason: str                   # one line
    at_byte: int | None = None    # offset in the (storage) file where the damage begins


@dataclass(frozen=True)
class AutopilotMessage:
    """A text the vehicle's own software logged (ArduPilot's STATUSTEXT or MSG, an error
    record, PX4's logged messages), at a time on the log's clock."""

    time_ns: int
    text: str
    # MAVLink's MAV_SEVERITY (syslog's levels): 0 emergency … 4 warning … 7 debug; None where
    # the log does not say (a DataFlash MSG record).
    severity: int | None = None
    # A status already wrong at its first report (a hardware status of a ROS log): how the
    # log began, not an event of it.
    standing: bool = False


@dataclass(frozen=True, eq=False)
class Series:
    """One signal: ``values`` (float64) at ``times_ns`` (int64), in the log's order."""

    times_ns: np.ndarray
    values: np.ndarray
    name: str = ""

    def __len__(self) -> int:
        return int(self.values.size)

    def equals(self, other: "Series") -> bool:
        """The same samples at the same times (NaN equal to NaN)."""
        return np.array_equal(self.times_ns, other.times_ns) and np.array_equal(
            self.values, other.values, equal_nan=True)

    def where(self, keep: np.ndarray) -> "Series":
        return Series(self.times_ns[keep], self.values[keep], self.name)


@dataclass
class Signals:
    """Everything diagnosis needs from one log, on each signal's own time base."""

    path: Path
    format: str
    start_ns: int
    end_ns: int
    series: dict[str, Series]
    markers: list[SegmentMarker] = field(default_factory=list)
    topics: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    damage: Damage | None = None          # None: the whole file was read
    messages_read: int = 0                # messages of the profile's topics
    namespace: str = ""                   # the ROS namespace the topics were read under
    autopilot_messages: list[AutopilotMessage] = field(default_factory=list)

    def cropped(self, start_ns: int | None, end_ns: int | None) -> "Signals":
        """The part of the log from ``start_ns`` to ``end_ns`` (None: its own start or end),
        on the same clock: every signal's and marker's samples outside it left out."""
        low = self.start_ns if start_ns is None else max(self.start_ns, start_ns)
        high = self.end_ns if end_ns is None else min(self.end_ns, end_ns)
        return replace(
            self, start_ns=low, end_ns=high,
            series={name: s.where((s.times_ns >= low) & (s.times_ns <= high))
                    for name, s in self.series.items()},
            markers=[m for m in self.markers if low <= m.time_ns <= high],
            autopilot_messages=[m for m in self.autopilot_messages
                                if low <= m.time_ns <= high])
