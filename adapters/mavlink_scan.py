"""Walk the records of a tlog or DataFlash file without decoding payloads: where each
record starts, its message type, and the first place the framing breaks (the analysis
covers the records before it, and the report says so).

The walk is the only per-record Python; everything after it (times, counts, payload
decoding in `adapters.mavlink_columns`) works on whole arrays."""

import mmap
from array import array
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from adapters.packed import gather_words
from adapters.signals import Damage
from adapters.timebase import plausible_us, robust_span

DATAFLASH_FMT = 0x80
DATAFLASH_FMT_LENGTH = 89
DATAFLASH_HEADER_LENGTH = 3                  # A3 95 <type>
MAVLINK1_HEADER, MAVLINK2_HEADER = 6, 10     # magic … msgid
TLOG_TIME_LENGTH = 8                         # big-endian µs before each frame
NO_TIME, BAD_TIME = -1, -2                   # a record type without time; a corrupt time


@dataclass(frozen=True)
class DataflashFormat:
    """One FMT record: the payload layout of a message type."""

    name: str
    length: int          # whole record, header included
    types: str           # DataFlash format characters, one per column
    columns: tuple[str, ...]


@dataclass
class RecordIndex:
    """Every whole record of a file, in file order."""

    data: np.ndarray                       # the file, uint8, memory-mapped
    offsets: np.ndarray                    # int64: where each record starts
    type_ids: np.ndarray                   # int64: msgid (MAVLink) or type (DataFlash)
    names: dict[int, str]                  # type id → message name
    times_us: np.ndarray                   # int64 µs per record, or NO_TIME / BAD_TIME
    problem: Damage | None = None
    formats: dict[int, DataflashFormat] = field(default_factory=dict)

    @property
    def counts(self) -> Counter[str]:
        ids, counts = np.unique(self.type_ids, return_counts=True)
        return Counter({self.names.get(int(i), f"id {int(i)}"): int(n)
                        for i, n in zip(ids, counts, strict=True)})

    @property
    def span_us(self) -> tuple[int | None, int | None]:
        """First and last record time, ignoring corrupt and lone outlying times."""
        timed = self.times_us[self.times_us >= 0]
        first, last = robust_span(timed * 1000)
        return (None if first is None else first // 1000,
                None if last is None else last // 1000)

    def of_type(self, type_id: int) -> np.ndarray:
        """Record positions (into `offsets`) of one message type."""
        return np.flatnonzero(self.type_ids == type_id)


def _problem(size: int, position: int, what: str) -> Damage:
    return Damage(f"{what} at byte {position} of {size}: the recording was cut short or "
                  "damaged there; the analysis covers the records before it", position)


def _walk_tlog(data: mmap.mmap | bytes) -> "tuple[array[int], Damage | None]":
    """Records are an 8-byte big-endian µs time and a MAVLink 1 or 2 frame."""
    offsets, size, position = array("q"), len(data), 0
    while position < size:
        if position + TLOG_TIME_LENGTH + MAVLINK2_HEADER > size:
            return offsets, _problem(size, position, "the file ends inside a record")
        magic, length = data[position + 8], data[position + 9]
        if magic == 0xFE:
            frame = MAVLINK1_HEADER + length + 2
        elif magic == 0xFD:
            frame = MAVLINK2_HEADER + length + 2 + (13 if data[position + 10] & 1 else 0)
        else:
            return offsets, _problem(size, position, "bytes that are not a MAVLink frame")
        if position + TLOG_TIME_LENGTH + frame > size:
            return offsets, _problem(size, position, "the file ends inside a record")
        offsets.append(position)
        position += TLOG_TIME_LENGTH + frame
    return offsets, None


def tlog_frame_fields(data: np.ndarray, offsets: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per frame: MAVLink version (1 or 2), msgid, payload start and payload length."""
    frames = offsets + TLOG_TIME_LENGTH
    version2 = data[frames] == 0xFD
    v2_frames = np.where(version2, frames, 0)      # keeps the v2 reads inside the file
    msgid = np.where(version2,
                     data[v2_frames + 7].astype(np.int64) | data[v2_frames + 8].astype(
                         np.int64) << 8 | data[v2_frames + 9].astype(np.int64) << 16,
                     data[frames + 5])
    starts = frames + np.where(version2, MAVLINK2_HEADER, MAVLINK1_HEADER)
    return np.where(version2, 2, 1), msgid, starts, data[frames + 1].astype(np.int64)


def index_tlog(data: mmap.mmap | bytes, message_names: dict[int, str]) -> RecordIndex:
    raw = np.frombuffer(data, np.uint8)
    walked, problem = _walk_tlog(data)
    offsets = np.frombuffer(walked, np.int64) if walked else np.zeros(0, np.int64)
    _, msgid, _, _ = tlog_frame_fields(raw, offsets)
    times = _checked_times(gather_words(raw, offsets, ">u8"))
    return RecordIndex(raw, offsets, msgid.astype(np.int64), dict(message_names), times,
                       problem)


def _walk_dataflash(data: mmap.mmap | bytes
                    ) -> "tuple[array[int], dict[int, DataflashFormat], Damage | None]":
    """Records are ``A3 95 <type>`` and a payload whose length an FMT record declared."""
    offsets, size, position = array("q"), len(data), 0
    formats = {DATAFLASH_FMT: DataflashFormat("FMT", DATAFLASH_FMT_LENGTH, "BBnNZ",
                                              ("Type", "Length", "Name", "Format", "Columns"))}
    lengths = {DATAFLASH_FMT: DATAFLASH_FMT_LENGTH}
    while position < size:
        if position + DATAFLASH_HEADER_LENGTH > size:
            return offsets, formats, _problem(size, position, "the file ends inside a record")
        if data[position] != 0xA3 or data[position + 1] != 0x95:
            return offsets, formats, _problem(size, position,
                                              "bytes that are not a DataFlash record")
        kind = data[position + 2]
        length = lengths.get(kind)
        if length is None:
            return offsets, formats, _problem(size, position, "a record of an undeclared type")
        if position + length > size:
            return offsets, formats, _problem(size, position, "the file ends inside a record")
        if kind == DATAFLASH_FMT:
            declared = _parse_fmt(bytes(data[position:position + DATAFLASH_FMT_LENGTH]))
            if declared.length < DATAFLASH_HEADER_LENGTH or (
                    data[position + 3] == DATAFLASH_FMT
                    and declared.length != DATAFLASH_FMT_LENGTH):
                return offsets, formats, _problem(size, position, "an FMT record that cannot "
                                                  "be right (a length shorter than a header, "
                                                  "or FMT's own length changed)")
            formats[data[position + 3]] = declared
            lengths[data[position + 3]] = declared.length
        offsets.append(position)
        position += length
    return offsets, formats, None


def _parse_fmt(record: bytes) -> DataflashFormat:
    def text(raw: bytes) -> str:
        return raw.split(b"\0", 1)[0].decode("ascii", "replace")

    return DataflashFormat(text(record[5:9]), record[4], text(record[9:25]),
                           tuple(c for c in text(record[25:89]).split(",") if c))


# A record's time, where its format starts with one: (column, format characters, the
# stored word, µs per unit). ArduPilot 3.2 and before logged TimeMS (ms, 32 bits).
RECORD_CLOCKS = (("TimeUS", "Qq", "<u8", 1), ("TimeMS", "Ii", "<u4", 1000))


def index_dataflash(data: mmap.mmap | bytes) -> RecordIndex:
    """A record's time is the first payload word, where its format starts with a clock
    (`RECORD_CLOCKS`)."""
    raw = np.frombuffer(data, np.uint8)
    walked, formats, problem = _walk_dataflash(data)
    offsets = np.frombuffer(walked, np.int64) if walked else np.zeros(0, np.int64)
    type_ids = raw[offsets + 2].astype(np.int64)
    clock = np.full(256, -1)
    for type_id, declared in formats.items():
        clock[type_id] = next((k for k, (column, types, _, _) in enumerate(RECORD_CLOCKS)
                               if declared.columns[:1] == (column,)
                               and declared.types[:1] in types), -1)
    times = np.full(offsets.size, NO_TIME, np.int64)
    for k, (_, _, word, scale) in enumerate(RECORD_CLOCKS):
        has_time = clock[type_ids] == k
        starts = offsets[has_time] + DATAFLASH_HEADER_LENGTH
        times[has_time] = _checked_times(gather_words(raw, starts, word).astype(np.uint64)
                                         * np.uint64(scale))
    names = {type_id: declared.name for type_id, declared in formats.items()}
    return RecordIndex(raw, offsets, type_ids, names, times, problem, formats)


def _checked_times(raw_us: np.ndarray) -> np.ndarray:
    """uint64 µs as int64, with times no clock can show marked BAD_TIME."""
    times = raw_us.astype(np.int64)
    times[~plausible_us(raw_us.astype(np.float64))] = BAD_TIME
    return times


def index_file(path: Path, kind: str, message_names: dict[int, str] | None = None
               ) -> RecordIndex:
    """The file stays memory-mapped for as long as the index (and arrays cut from it) live."""
    with path.open("rb") as stream:
        data: mmap.mmap | bytes = (mmap.mmap(stream.fileno(), 0, access=mmap.ACCESS_READ)
                                   if path.stat().st_size else b"")
    return index_tlog(data, message_names or {}) if kind == "tlog" else index_dataflash(data)
