"""Pull one field out of every message of a topic at once, straight from the serialised
bytes (ROS 1 or little-endian CDR), instead of building a Python object per message.

The message definitions come from the log (rosbags' type store, the same definitions its
deserialisers are generated from). Walking a definition moves an array of read positions,
one per message, past the fields before the wanted one: fixed-size fields by a constant,
strings and sequences by the length each message stores. CDR aligns every primitive to its
size from the start of the body, and a non-empty sequence of primitives to its element
size, exactly as rosbags' deserialiser does; ROS 1 does not align.

Anything the walker does not handle (big-endian CDR, wide strings, a message shorter than
its definition) raises `NotColumnar`, and the adapter decodes that topic message by
message instead."""

from array import array
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from adapters.collect import SignalCollector
from adapters.fieldnames import message_fields, ros_field_paths
from adapters.fieldpath import parse_field_path
from adapters.packed import gather_words, gathered
from auvdiag_errors import LogError

PRIMITIVES = {"bool": "u1", "byte": "u1", "char": "u1", "int8": "i1", "uint8": "u1",
              "int16": "<i2", "uint16": "<u2", "int32": "<i4", "uint32": "<u4",
              "int64": "<i8", "uint64": "<u8", "float32": "<f4", "float64": "<f8"}
CDR_HEADER = 4                               # encapsulation kind and options
CDR_LITTLE_ENDIAN = (0x01, 0x03)             # CDR_LE, PL_CDR_LE


class NotColumnar(ValueError):
    """This field of these messages cannot be read column-wise."""


@dataclass(frozen=True)
class PlacedMessages:
    """Serialised messages of one topic where they lie: message i is
    ``data[starts[i]:ends[i]]`` (a log's own bytes, read in place, or a gathered batch)."""

    cdr: bool
    data: np.ndarray            # uint8
    starts: np.ndarray          # int64
    ends: np.ndarray            # int64
    times_ns: np.ndarray        # int64

    def placed(self) -> "PlacedMessages":
        return self

    def messages(self) -> list[bytes]:
        """Each message's bytes (for the per-message fallback)."""
        return [bytes(self.data[a:b]) for a, b in zip(self.starts.tolist(), self.ends.tolist(),
                                                       strict=True)]


@dataclass
class RawMessages:
    """The serialised messages of one topic, appended as the log is read."""

    cdr: bool
    buffer: bytearray = field(default_factory=bytearray)
    starts: "array[int]" = field(default_factory=lambda: array("q"))
    times_ns: "array[int]" = field(default_factory=lambda: array("q"))

    def append(self, time_ns: int, raw: bytes | memoryview) -> None:
        self.starts.append(len(self.buffer))
        self.times_ns.append(time_ns)
        self.buffer += raw

    def extend(self, times_ns: np.ndarray, block: np.ndarray, begins: np.ndarray) -> None:
        """Many messages stored back to back in ``block``, each from its ``begins``."""
        self.starts.frombytes((begins + len(self.buffer)).astype(np.int64).tobytes())
        self.times_ns.frombytes(times_ns.astype(np.int64).tobytes())
        self.buffer += np.ascontiguousarray(block).data

    def __len__(self) -> int:
        return len(self.starts)

    def placed(self) -> PlacedMessages:
        """The messages back to back in the buffer, each ending where the next begins."""
        starts = np.frombuffer(self.starts, np.int64) if len(self) else np.zeros(0, np.int64)
        data = np.frombuffer(self.buffer, np.uint8)
        ends = np.append(starts[1:], data.size)[:starts.size]
        times = np.frombuffer(self.times_ns, np.int64) if len(self) else np.zeros(0, np.int64)
        return PlacedMessages(self.cdr, data, starts, ends, times)

    def messages(self) -> list[bytes]:
        return self.placed().messages()


class ColumnReader:
    """Field paths → one NumPy column per path (numbers) or object column (strings)."""

    def __init__(self, messages: RawMessages | PlacedMessages, msgtype: str,
                 typestore: Any) -> None:
        placed = messages.placed()
        self.msgtype, self.typestore, self.cdr = msgtype, typestore, placed.cdr
        self.data = self.raw = placed.data
        starts, self.ends = placed.starts, placed.ends
        if self.cdr:
            if starts.size and not np.isin(self.data[starts + 1], CDR_LITTLE_ENDIAN).all():
                raise NotColumnar("big-endian CDR")
            starts = starts + CDR_HEADER
        self.origin = starts

    def column(self, path: str) -> np.ndarray:
        rows = np.arange(self.origin.size)
        return self._descend(("NAME", self.msgtype), parse_field_path(path), self.origin, rows)

    # -- reading: ``rows`` says which messages ``positions`` belong to ---------------------
    def _align(self, positions: np.ndarray, size: int, rows: np.ndarray) -> np.ndarray:
        if not self.cdr or size == 1:
            return positions
        size, origin = min(size, 8), self.origin[rows]
        return origin + (positions - origin + size - 1) // size * size

    def _read(self, positions: np.ndarray, dtype: np.dtype, rows: np.ndarray) -> np.ndarray:
        if (positions + dtype.itemsize > self.ends[rows]).any():
            raise NotColumnar("a message is shorter than its definition")
        return gather_words(self.data, positions, dtype.str)

    def _string_bounds(self, positions: np.ndarray, rows: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
        """Where each string's text starts, and where the field after it starts."""
        positions = self._align(positions, 4, rows)
        lengths = self._read(positions, np.dtype("<u4"), rows).astype(np.int64)
        after = positions + 4 + lengths
        if (after > self.ends[rows]).any():
            raise NotColumnar("a string runs past its message")
        return positions + 4, after

    def _strings(self, positions: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The strings as bytes objects (an object column)."""
        starts, after = self._string_bounds(positions, rows)
        text_ends = after - 1 if self.cdr else after          # CDR counts the trailing NUL
        raw = self.raw
        return np.array([bytes(raw[a:b]) for a, b in zip(starts.tolist(), text_ends.tolist(),
                                                          strict=True)], object)

    # -- walking the definition -----------------------------------------------------------
    def _node(self, desc: tuple[Any, ...]) -> tuple[str, Any]:
        kind, detail = desc
        return kind.name, detail

    def _fields(self, typename: str) -> list[tuple[str, tuple[str, Any]]]:
        return [(name, self._node(desc))
                for name, desc in message_fields(self.typestore, typename)]

    def _counts(self, node: tuple[str, Any], positions: np.ndarray, rows: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """An array's element count per message, and where its elements start."""
        kind, detail = node
        if kind == "ARRAY":
            return np.full(positions.size, detail[1], np.int64), positions
        positions = self._align(positions, 4, rows)
        counts = self._read(positions, np.dtype("<u4"), rows).astype(np.int64)
        if (positions + 4 + counts > self.ends[rows]).any():
            # Every element takes a byte at least: a larger count is damage, and walking it
            # element by element would take as long as the count says.
            raise NotColumnar("a sequence count runs past its message")
        return counts, positions + 4

    def _skip(self, node: tuple[str, Any], positions: np.ndarray, rows: np.ndarray
              ) -> np.ndarray:
        kind, detail = node
        if kind == "BASE":
            typename = detail[0]
            if typename == "string":
                return self._string_bounds(positions, rows)[1]
            if typename not in PRIMITIVES:
                raise NotColumnar(f"type {typename}")
            size = np.dtype(PRIMITIVES[typename]).itemsize
            return self._align(positions, size, rows) + size
        if kind == "NAME":
            for _, child in self._fields(detail):
                positions = self._skip(child, positions, rows)
            return positions
        element = self._node(detail[0])
        counts, positions = self._counts(node, positions, rows)
        if element[0] == "BASE" and element[1][0] in PRIMITIVES:
            size = np.dtype(PRIMITIVES[element[1][0]]).itemsize
            aligned = np.where(counts > 0, self._align(positions, size, rows), positions)
            return aligned + counts * size
        positions = positions.copy()
        for index in range(int(counts.max(initial=0))):     # strings, messages: one by one
            present = counts > index
            positions[present] = self._skip(element, positions[present], rows[present])
        return positions

    def _descend(self, node: tuple[str, Any], steps: tuple[str | int, ...],
                 positions: np.ndarray, rows: np.ndarray) -> np.ndarray:
        kind, detail = node
        if not steps:
            if kind == "BASE" and detail[0] == "string":
                return self._strings(positions, rows)
            if kind == "BASE" and detail[0] in PRIMITIVES:
                dtype = np.dtype(PRIMITIVES[detail[0]])
                return self._read(self._align(positions, dtype.itemsize, rows), dtype, rows)
            raise NotColumnar(f"{kind.lower()} is not a value")
        step, rest = steps[0], steps[1:]
        if kind == "NAME" and isinstance(step, str):
            for name, child in self._fields(detail):
                if name == step:
                    return self._descend(child, rest, positions, rows)
                positions = self._skip(child, positions, rows)
            raise KeyError(f"{detail} has no field {step!r}")
        if kind in ("ARRAY", "SEQUENCE") and isinstance(step, int):
            element = self._node(detail[0])
            counts, positions = self._counts(node, positions, rows)
            if (counts <= step).any():
                raise IndexError(f"index {step} outside an array of {int(counts.min())}")
            for _ in range(step):
                positions = self._skip(element, positions, rows)
            return self._descend(element, rest, positions, rows)
        raise KeyError(f"cannot apply {step!r} to a {kind.lower()}")


class TopicBatches:
    """Serialised messages gathered per topic and handed to the collector a batch at a
    time (so memory stays bounded however long the log): column-wise when every field the
    profile reads there can be walked, else deserialised one message at a time (which also
    gives the usual error when a field does not resolve)."""

    BATCH_BYTES = 8 << 20

    def __init__(self, collector: SignalCollector, msgtypes: dict[str, str], cdr: bool,
                 typestore: Any, deserialize: Callable[[bytes, str], Any]) -> None:
        self.collector, self.msgtypes, self.cdr = collector, msgtypes, cdr
        self.typestore, self.deserialize = typestore, deserialize
        self.pending: dict[str, RawMessages] = {}
        self.decoded: set[str] = set()      # topics with a message read
        # Per topic, messages left out as undecodable since the last flush, and why.
        self.left_out: dict[str, tuple[int, Exception]] = {}

    def append(self, topic: str, time_ns: int, raw: bytes | memoryview) -> None:
        if not self.collector.accepts_time(time_ns):
            return
        batch = self._batch(topic)
        batch.append(time_ns, raw)
        self._hand_over_if_full(topic, batch)

    def extend(self, topic: str, times_ns: np.ndarray, data: np.ndarray, starts: np.ndarray,
               ends: np.ndarray) -> None:
        """Many messages of a topic at once: message i is ``data[starts[i]:ends[i]]``."""
        keep = self.collector.accepts_times(times_ns)
        batch = self._batch(topic)
        batch.extend(times_ns[keep], *gathered(data, starts[keep], ends[keep]))
        self._hand_over_if_full(topic, batch)

    def hand_over_in_place(self, topic: str, times_ns: np.ndarray, data: np.ndarray,
                           starts: np.ndarray, ends: np.ndarray) -> None:
        """Many messages of a topic read where they lie in ``data`` (the log's own bytes),
        handed over now: no copy, and ``data`` is not kept. Messages batched for the
        topic before them go first."""
        keep = self.collector.accepts_times(times_ns)
        pending = self.pending.pop(topic, None)
        if pending is not None:
            self._add(topic, pending.placed())
        self._add(topic, PlacedMessages(self.cdr, data, starts[keep], ends[keep],
                                        times_ns[keep]))

    def _batch(self, topic: str) -> RawMessages:
        batch = self.pending.get(topic)
        if batch is None:        # not setdefault: that would build a batch per message
            batch = self.pending[topic] = RawMessages(self.cdr)
        return batch

    def _hand_over_if_full(self, topic: str, batch: RawMessages) -> None:
        if len(batch.buffer) >= self.BATCH_BYTES:
            self._add(topic, self.pending.pop(topic).placed())

    def flush(self) -> None:
        """Hand every pending batch over. A batch holding a message its definition does not
        describe keeps the messages before that one, and does not keep the other topics'
        batches from the collector: the first such failure is raised after them all."""
        failure: Exception | None = None
        while self.pending:
            topic, batch = self.pending.popitem()
            try:
                self._add(topic, batch.placed())
            except LogError:
                raise
            except Exception as error:  # damaged data surfaces as several unrelated types
                failure = failure or error
        for topic, (count, first) in self.left_out.items():
            reason = (f"{count} message(s) of {topic} left out: their bytes do not match "
                      f"the topic's definition (first: {first})")
            self.collector.notes.append(reason)
            self.collector.damaged(reason)
        self.left_out.clear()
        if failure is not None:
            raise failure

    def fill(self, feed: Callable[[], None]) -> None:
        """Run ``feed`` (which appends the log's messages) and hand everything over. Damage
        met on the way keeps what came before it, noted; damage before any message is an
        error."""
        damage: Exception | None = None
        try:
            feed()
        except (LogError, MemoryError):
            raise
        except Exception as error:  # damaged data surfaces as several unrelated types
            damage = error
        try:
            self.flush()
        except LogError:
            raise
        except Exception as error:  # a message its own definition does not describe
            damage = damage or error
        if damage is None:
            return
        collector = self.collector
        if collector.count == 0:
            raise LogError(collector.path, f"damaged log: {damage}") from None
        reason = (f"log damaged after {collector.count} messages ({damage}); analysed "
                  "the part before the damage")
        collector.notes.append(reason)
        collector.damaged(reason)

    def _add(self, topic: str, batch: PlacedMessages) -> None:
        msgtype = self.msgtypes[topic]
        try:
            reader = ColumnReader(batch, msgtype, self.typestore)
            columns = {}
            for path in self.collector.field_paths(topic):
                try:
                    columns[path] = reader.column(path)
                except (KeyError, IndexError):
                    if not self.collector.sources.tentative:
                        raise      # read one by one, for the error naming the field
        except (NotColumnar, KeyError, IndexError):
            self._add_one_by_one(topic, msgtype, batch)
            return
        self.collector.add_columns(topic, batch.times_ns, columns.__getitem__,
                                   ros_field_paths(self.typestore, msgtype))
        self.decoded.add(topic)

    def _add_one_by_one(self, topic: str, msgtype: str, batch: PlacedMessages) -> None:
        """Each message deserialised alone. One that does not decode is left out and
        counted, and the read goes on: every ROS storage frames its messages, so the next
        one is whole. Where none has decoded yet for the topic, its definition may not
        describe it at all: that is raised (the read ends there, as at any damage)."""
        first: Exception | None = None
        count = 0
        for time_ns, raw in zip(batch.times_ns.tolist(), batch.messages(), strict=True):
            try:
                message = self.deserialize(raw, msgtype)
            except Exception as error:  # damaged data surfaces as several unrelated types
                first, count = first or error, count + 1
                continue
            self.collector.add(topic, time_ns, message)
            self.decoded.add(topic)
        if first is None:
            return
        if topic not in self.decoded:
            raise first
        earlier, earliest = self.left_out.get(topic, (0, first))
        self.left_out[topic] = (earlier + count, earliest)
