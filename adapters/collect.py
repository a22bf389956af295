"""Turn decoded messages into `Signals`: one piece of code shared by every adapter."""

from array import array
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from adapters.extractor import ColumnSource, Extractor
from adapters.fieldnames import closest_first, object_field_paths, unresolved
from adapters.fieldpath import field_of, resolves
from adapters.namespace import ROOT, Resolution, naming_hint, normalised, resolve, under
from adapters.ros_words import WordsRead, word_paths
from adapters.signals import (
    Damage,
    LogSources,
    SegmentMarker,
    Series,
    Signals,
    as_text,
    fallback_name,
    readable_column,
)
from adapters.timebase import MAX_TIME_NS, spikes
from auvdiag_errors import LogError

# How a log that lacks a signal the profile names is reported (callers match on it).
MISSING_SIGNALS = "no messages for signal(s)"
# How far a container's recorded start or end may lie outside the data it holds.
MAX_LEAD_NS = 24 * 3600 * 1_000_000_000
def _with_state_before(flag: Series, start_ns: int) -> Series:
    """A flag logged only when it changes was, before its first record, the other way."""
    if not len(flag) or int(flag.times_ns[0]) <= start_ns:
        return flag
    return Series(np.concatenate(([start_ns], flag.times_ns)).astype(np.int64),
                  np.concatenate(([float(flag.values[0] == 0)], flag.values)), flag.name)


class SignalCollector:
    """Accumulates the profile's signals and markers from messages as an adapter reads them.

    Adapters call `add(topic, time_ns, message)` for every message of a wanted topic and
    `finish(...)` at the end; field resolution, scaling, filters and marker parsing live here.
    """

    def __init__(self, path: Path, sources: LogSources) -> None:
        self.path, self.sources = path, sources
        self.wanted = sources.wanted
        self.extractors = [Extractor(name, source) for name, source in self.wanted.items()]
        self.words = WordsRead()
        self._apply(Resolution(normalised(sources.namespace or ROOT),
                               {topic: topic for topic in sources.topics}))
        self.namespace_fixed = False      # set once the log's topics decided the namespace
        self.claimed: set[str] = set()    # profile topics `wants` found a name for
        self.refused: set[str] = set()    # log topics `wants` said no to
        # Typed arrays: 8 bytes a sample, not a Python object, so long dives stay small.
        self.times: dict[str, array[int]] = {name: array("q") for name in self.wanted}
        self.values: dict[str, array[float]] = {name: array("d") for name in self.wanted}
        self.markers: list[SegmentMarker] = []
        self.count = 0
        self.notes: list[str] = []
        self.damage: Damage | None = None
        self.impossible_times = 0
        # Signals whose `where` matched no message: the values the first key did take.
        self.filtered_out: dict[str, list[str]] = {}

    def accepts_time(self, time_ns: int) -> bool:
        """False (and counted) for a stored time no clock can show: a corrupted record."""
        if 0 <= time_ns < MAX_TIME_NS:
            return True
        self.impossible_times += 1
        return False

    def accepts_times(self, times_ns: np.ndarray) -> np.ndarray:
        """`accepts_time` for many stored times at once: which to keep."""
        keep = (times_ns >= 0) & (times_ns < MAX_TIME_NS)
        self.impossible_times += int(keep.size - np.count_nonzero(keep))
        return keep

    def damaged(self, reason: str, at_byte: int | None = None) -> None:
        """The file could be read only up to here (the first damage found is kept)."""
        if self.damage is None:
            self.damage = Damage(reason, at_byte)

    def _apply(self, resolution: Resolution) -> None:
        """Read the profile's topics under the log's names for them."""
        self.namespace, self.names = resolution.namespace, resolution.names
        self.by_topic: dict[str, list[Extractor]] = {}
        for extractor in self.extractors:
            self.by_topic.setdefault(self.names[extractor.source.topic], []).append(extractor)
        segment = self.sources.segment
        self.segment_topic = None if segment is None else self.names[segment.topic]
        self.word_topics = {word.topic if word.at_root else under(self.namespace, word.topic):
                            word for word in self.sources.words}
        self.topics: set[str] = set(self.names.values()) | self.word_topics.keys()  # log's names

    def resolve_topics(self, available: Iterable[str]) -> None:
        """The log's topics, known before reading (an index, a summary): the namespace the
        profile's topics are under is found from them (`adapters.namespace`)."""
        if not self.namespace_fixed:
            self._apply(resolve(self.path, self.sources.topics, available,
                                self.sources.namespace))
            self.namespace_fixed = True

    def wants(self, topic: str) -> bool:
        """Whether to read ``topic``, for readers that meet the topics as they read (no
        index): a profile topic is read under the first name it shows up with, at the root
        or under the namespace the first namespaced one showed (`require_topics` checks
        the choice against all of the log's topics at the end)."""
        if topic in self.topics or self.namespace_fixed or topic in self.refused:
            return topic in self.topics
        for wanted in self.sources.topics - self.claimed:
            suffix = "/" + wanted.lstrip("/")
            namespace = normalised(topic[:-len(suffix)]) if topic.endswith(suffix) else None
            if namespace is None or (namespace and namespace != self.namespace and (
                    self.namespace or self.sources.namespace is not None)):
                continue
            self.claimed.add(wanted)
            self._apply(Resolution(namespace or self.namespace,
                                   {**self.names, wanted: topic}))
            return True
        self.refused.add(topic)       # salvage asks once a message
        return False

    def field_paths(self, topic: str) -> list[str]:
        """Every field path read on ``topic``: values, `where` filters, segment labels."""
        paths = [path for extractor in self.by_topic.get(topic, ())
                 for path in (*extractor.source.paths, *(k for k, _ in extractor.source.where))]
        segment = self.sources.segment
        if segment is not None and self.segment_topic == topic:
            paths.append(segment.field)
        word = self.word_topics.get(topic)
        if word is not None:
            paths += word_paths(word)
        return list(dict.fromkeys(paths))

    def _only_words(self, topic: str) -> bool:
        """The topic is read for what the vehicle's software said, and for nothing else (its
        messages are not counted among the profile's)."""
        return topic in self.word_topics and topic not in self.by_topic \
            and topic != self.segment_topic

    def add(self, topic: str, time_ns: int, message: Any) -> None:
        if not self.accepts_time(time_ns):
            return
        if topic in self.word_topics:
            self.words.add_message(self.word_topics[topic], time_ns, message, field_of)
            if self._only_words(topic):
                return
        self.count += 1
        segment = self.sources.segment
        if segment is not None and topic == self.segment_topic:
            text = as_text(field_of(message, segment.field))
            if text.startswith(segment.prefix):
                self.markers.append(SegmentMarker(time_ns, text[len(segment.prefix):].strip()))
        for extractor in self.by_topic.get(topic, ()):
            try:
                if extractor.where and not extractor.matches(message):
                    continue
                raw = extractor.get(message)
                if raw is None:          # a JSON message's null: no reading at this time
                    continue
                source = extractor.source
                # A text is read only through a `values` map (a mode's name).
                value = raw if source.mapped and isinstance(raw, str | bytes) \
                    else np.float64(float(raw))
            except (AttributeError, IndexError, KeyError, TypeError, ValueError):
                if self.sources.tentative:
                    continue
                wrong = next((key for key in (*(k for k, _ in extractor.source.where),
                                              *extractor.source.paths)
                              if not resolves(message, key)), extractor.source.field)
                raise LogError(self.path, unresolved(
                    topic, wrong, extractor.name, object_field_paths(message))) from None
            converted = float(source.convert(value))
            if source.mapped and not np.isfinite(converted):
                continue                  # a value the source's map does not list
            self.times[extractor.name].append(time_ns)
            self.values[extractor.name].append(converted)

    def add_columns(self, topic: str, times_ns: np.ndarray, column: ColumnSource,
                    fields: Sequence[str]) -> None:
        """Every message of ``topic`` at once, as columns (readers that decode whole
        message types into arrays). Same result as `add` per message. ``fields``: the
        paths these messages offer (for errors, and to find sensor instances)."""
        rows = times_ns.size
        if topic in self.word_topics:
            self.words.add_columns(self.word_topics[topic], times_ns, column)
            if self._only_words(topic):
                return
        self.count += rows
        if self.sources.segment is not None and topic == self.segment_topic:
            self._add_marker_columns(topic, times_ns, column, fields)
        for extractor in self.by_topic.get(topic, ()):
            wanted = extractor.source.field
            filters = extractor.filters(fields)
            try:
                for wanted in (*(key for key, _ in filters), *extractor.source.paths):
                    column(wanted)
                keep = extractor.rows_matching(column, rows, fields) if filters else slice(None)
                numbers = extractor.column(column)[keep]
            except (IndexError, KeyError, TypeError, ValueError):
                if self.sources.tentative:
                    continue
                raise LogError(self.path, unresolved(topic, wanted, extractor.name,
                                                     fields)) from None
            readable = readable_column(numbers, extractor.source)
            if readable is None and self.sources.tentative:
                continue
            if readable is None:
                raise LogError(self.path, f"{topic} field {wanted!r} (signal {extractor.name}) "
                                          f"holds {numbers.dtype}, not numbers")
            numbers = readable
            if filters and not numbers.size and rows:
                key = filters[0][0]
                self.filtered_out[extractor.name] = sorted(
                    {as_text(v) for v in np.unique(column(key)).tolist()})
            mixed = extractor.mixed_instances(column, fields, keep)
            if mixed is not None:
                key, instances = mixed
                raise LogError(self.path, f"{topic} holds {len(instances)} sensor instances "
                               f"({key} = {', '.join(instances)}) that signal "
                               f"{extractor.name} would merge: choose one with where = "
                               f"{{ {key} = {instances[0]} }} in the profile, or set "
                               "merge_instances = true")
            values, times = extractor.source.convert(numbers), times_ns[keep]
            if extractor.source.mapped:       # values the source's map does not list
                listed = np.isfinite(values)
                values, times = values[listed], times[listed]
            self.times[extractor.name].frombytes(times.astype(np.int64).tobytes())
            self.values[extractor.name].frombytes(values.tobytes())

    def _add_marker_columns(self, topic: str, times_ns: np.ndarray, column: ColumnSource,
                            fields: Sequence[str]) -> None:
        segment = self.sources.segment
        assert segment is not None
        try:
            texts = column(segment.field).tolist()
        except (IndexError, KeyError, TypeError, ValueError):
            raise LogError(self.path, unresolved(topic, segment.field, "segment markers",
                                                 fields)) from None
        for time_ns, raw in zip(times_ns.tolist(), texts, strict=True):
            text = as_text(raw)
            if text.startswith(segment.prefix):
                self.markers.append(SegmentMarker(time_ns, text[len(segment.prefix):].strip()))

    def require_topics(self, available: Iterable[str], where: str = "") -> None:
        """Every signal topic is among the log's topics ``available`` (under its namespace,
        which this settles), else a `LogError`; ``where``: "in the readable part"."""
        available = set(available)
        settled = resolve(self.path, self.sources.topics, available, self.sources.namespace)
        if settled.names != self.names and (self.namespace_fixed or self.count):
            raise LogError(self.path, f"the profile's topics are under the namespace "
                           f"{settled.namespace or '/'}, but the first ones read were under "
                           f"{self.namespace or '/'}: " + naming_hint(settled.namespace))
        self._apply(settled)
        self.namespace_fixed = True
        optional = self.sources.fallbacks.keys() | self.sources.optional
        missing = sorted({self.names[s.topic] for n, s in self.sources.signals.items()
                          if n not in optional} - available)
        if missing:
            raise LogError(self.path, f"missing topic(s) {', '.join(missing)}{where}")

    def finish(self, fmt: str, start_ns: int | None, end_ns: int | None,
               topics: dict[str, str], require_all: bool = True,
               time_ordered: bool = False) -> Signals:
        """The collected signals. A sample whose time is a lone spike (a corrupted record)
        is dropped and counted. With ``require_all`` a signal without samples is an error;
        without it (inspection) such a signal is simply absent. ``time_ordered``: the
        format defines order by time stamp, not storage (MCAP chunks may come in any
        order), so each signal is sorted here and a later jump back is no clock reset."""
        if self.impossible_times:
            self.notes.append(f"{self.impossible_times} message(s) with an impossible time "
                              "left out")
        self._use_fallbacks()
        if self.namespace:
            self.notes.append(f"topics read under the namespace {self.namespace}")
        empty = sorted(name for name, times in self.times.items() if not times)
        # An optional signal without samples is left out; what stands in for it is the
        # reader's to say.
        lacking = [name for name in empty if name not in self.sources.optional]
        if lacking and require_all:
            where = ", ".join(self._why_empty(n) for n in lacking)
            raise LogError(self.path, f"{MISSING_SIGNALS} {where}")
        series = {name: self._series(name, time_ordered) for name in self.times
                  if name not in empty}
        firsts = [int(s.times_ns.min()) for s in series.values() if len(s)]
        lasts = [int(s.times_ns.max()) for s in series.values() if len(s)]
        firsts += [m.time_ns for m in self.markers]
        # The container's own span (index, statistics) widens the data's, unless it is so
        # far from it that the container's record of it must be damaged.
        if start_ns is not None and (not firsts or 0 <= min(firsts) - start_ns <= MAX_LEAD_NS):
            firsts.append(start_ns)
        if end_ns is not None and (not lasts or 0 <= end_ns - max(lasts) <= MAX_LEAD_NS):
            lasts.append(end_ns)
        first = min(firsts, default=None)
        last = max(lasts, default=first)
        for name, values in series.items():
            if self.wanted[name].changes_only and first is not None:
                series[name] = _with_state_before(values, first)
        return Signals(path=self.path, format=fmt,
                       start_ns=0 if first is None else first,
                       end_ns=0 if last is None else last,
                       series=series, markers=self.markers, topics=topics, notes=self.notes,
                       damage=self.damage, messages_read=self.count,
                       namespace=self.namespace, autopilot_messages=self.words.messages())

    def _use_fallbacks(self) -> None:
        """A signal without a message of its own source takes its fallback's samples."""
        for name, source in self.sources.fallbacks.items():
            alternate = fallback_name(name)
            if alternate not in self.times:
                continue
            times, values = self.times.pop(alternate), self.values.pop(alternate)
            if not self.times[name] and times:
                self.times[name], self.values[name] = times, values
                self.wanted[name] = source
                own = self.sources.signals[name]
                self.notes.append(f"{name} from {source.topic}.{source.field} (no {own.topic} "
                                  "message in this log)")

    def _why_empty(self, name: str) -> str:
        source = self.wanted[name]
        offered = self.filtered_out.get(name)
        if offered is None:
            return f"{name} ({self.names.get(source.topic, source.topic)})"
        wanted = " and ".join(f"{key} = {value}" for key, value in source.where)
        return (f"{name} ({source.topic} has no message with {wanted}; its values: "
                f"{', '.join(closest_first(source.where[0][1], offered))})")

    def _series(self, name: str, time_ordered: bool) -> Series:
        times = np.frombuffer(self.times[name], dtype=np.int64)
        values = np.frombuffer(self.values[name], dtype=np.float64)
        if time_ordered:
            order = np.argsort(times, kind="stable")
            times, values = times[order], values[order]
        corrupt = spikes(times)
        if corrupt.any():
            self.notes.append(f"{name}: {int(corrupt.sum())} sample(s) with a corrupted "
                              "timestamp left out")
            times, values = times[~corrupt], values[~corrupt]
        return Series(times, values, name)
