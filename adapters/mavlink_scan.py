"""Walk the records of a tlog or DataFlash file without decoding payloads: counts per
message type, first and last time, and the first place the framing breaks (pymavlink
stops or resyncs there silently, so this is how a report learns what was lost)."""

import mmap
import struct
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

DATAFLASH_FMT = 0x80
DATAFLASH_FMT_LENGTH = 89


@dataclass
class RecordScan:
    counts: Counter[str] = field(default_factory=Counter)
    first_us: int | None = None
    last_us: int | None = None
    problem: str | None = None


def _problem(size: int, position: int, what: str) -> str:
    return (f"{what} at byte {position} of {size}: the recording was cut short or damaged "
            "there; the analysis covers the records before it")


def scan_tlog(data: bytes | mmap.mmap, message_names: dict[int, str]) -> RecordScan:
    """Records are an 8-byte big-endian µs time and a MAVLink 1 or 2 frame."""
    scan, size, position = RecordScan(), len(data), 0
    while position < size:
        if position + 18 > size:
            scan.problem = _problem(size, position, "the file ends inside a record")
            break
        magic, length = data[position + 8], data[position + 9]
        if magic == 0xFE:
            frame, msgid = 6 + length + 2, data[position + 13]
        elif magic == 0xFD:
            frame = 10 + length + 2 + (13 if data[position + 10] & 1 else 0)
            msgid = int.from_bytes(data[position + 15:position + 18], "little")
        else:
            scan.problem = _problem(size, position, "bytes that are not a MAVLink frame")
            break
        if position + 8 + frame > size:
            scan.problem = _problem(size, position, "the file ends inside a record")
            break
        (time_us,) = struct.unpack_from(">Q", data, position)
        scan.first_us = time_us if scan.first_us is None else scan.first_us
        scan.last_us = time_us
        scan.counts[message_names.get(msgid, f"id {msgid}")] += 1
        position += 8 + frame
    return scan


def scan_dataflash(data: bytes | mmap.mmap) -> RecordScan:
    """Records are ``A3 95 <type>`` and a payload whose length an FMT record declared;
    TimeUS, when a format starts with it, is the first 8 payload bytes."""
    scan, size, position = RecordScan(), len(data), 0
    formats: dict[int, tuple[int, str, bool]] = {DATAFLASH_FMT: (DATAFLASH_FMT_LENGTH, "FMT",
                                                                 False)}
    while position < size:
        if position + 3 > size:
            scan.problem = _problem(size, position, "the file ends inside a record")
            break
        if data[position] != 0xA3 or data[position + 1] != 0x95:
            scan.problem = _problem(size, position, "bytes that are not a DataFlash record")
            break
        known = formats.get(data[position + 2])
        if known is None:
            scan.problem = _problem(size, position, "a record of an undeclared type")
            break
        length, name, timed = known
        if position + length > size:
            scan.problem = _problem(size, position, "the file ends inside a record")
            break
        if data[position + 2] == DATAFLASH_FMT:
            declared = bytes(data[position + 5:position + 9]).rstrip(b"\0").decode("ascii",
                                                                                    "replace")
            columns = bytes(data[position + 25:position + 89])
            formats[data[position + 3]] = (data[position + 4], declared,
                                           columns.startswith(b"TimeUS"))
        elif timed:
            (time_us,) = struct.unpack_from("<Q", data, position + 3)
            scan.first_us = time_us if scan.first_us is None else min(scan.first_us, time_us)
            scan.last_us = time_us if scan.last_us is None else max(scan.last_us, time_us)
        scan.counts[name] += 1
        position += length
    return scan


def scan_file(path: Path, kind: str, message_names: dict[int, str] | None = None
              ) -> RecordScan:
    with path.open("rb") as stream, mmap.mmap(stream.fileno(), 0, access=mmap.ACCESS_READ) as m:
        return scan_tlog(m, message_names or {}) if kind == "tlog" else scan_dataflash(m)
