"""ArduPilot DataFlash logs (.bin). pymavlink reads them but has no writer, so the records are
packed here: every record is ``A3 95 <type>`` and a little-endian payload described by an
FMT record (type 128) earlier in the file."""

import struct
from pathlib import Path

from adapters.signals import OPERATING
from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import Record, dive_records, family_sources
from auvdiag_cli.vehicle.profile import Profile

HEADER = b"\xa3\x95"
FMT_TYPE = 128
# DataFlash format characters -> struct codes (n, N, Z are fixed-size strings).
STRUCT_CODES = {"Q": "Q", "H": "H", "B": "B", "f": "f", "n": "4s", "N": "16s", "Z": "64s"}


class _Message:
    def __init__(self, type_id: int, name: str, fmt: str, columns: str) -> None:
        self.type_id, self.name, self.fmt, self.columns = type_id, name, fmt, columns
        self.struct = struct.Struct("<" + "".join(STRUCT_CODES[c] for c in fmt))

    @property
    def length(self) -> int:
        return 3 + self.struct.size

    def pack(self, *values: object) -> bytes:
        return HEADER + bytes([self.type_id]) + self.struct.pack(*values)


FMT = _Message(FMT_TYPE, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
# ArduPilot's own layouts of the records a profile is likely to read; any other record is
# written as TimeUS and the fields the profile reads (floats; `where` fields as text).
KNOWN_LAYOUTS = {
    "RCOU": ("Q" + "H" * 14, "TimeUS," + ",".join(f"C{i}" for i in range(1, 15))),
    "IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    "MSG": ("QZ", "TimeUS,Message"),
}
FIRST_TYPE_ID = 34


def _formats(profile: Profile) -> dict[str, _Message]:
    """One record format per message name the profile reads, plus MSG for the banner."""
    sources = family_sources(profile, "dataflash")
    fields: dict[str, list[str]] = {"MSG": []}
    where: dict[str, list[str]] = {}
    for source in sources.signals.values():
        fields.setdefault(source.topic, []).append(source.field)
        where.setdefault(source.topic, [k for k, _ in source.where])
    if sources.segment is not None:
        fields.setdefault(sources.segment.topic, []).append(sources.segment.field)
    formats = {}
    for type_id, (name, used) in enumerate(fields.items(), FIRST_TYPE_ID):
        if name in KNOWN_LAYOUTS:
            fmt, columns = KNOWN_LAYOUTS[name]
        else:
            texts = where.get(name, [])
            numbers = [f for f in dict.fromkeys(used) if f not in texts]
            fmt = "Q" + "f" * len(numbers) + "N" * len(texts)
            columns = ",".join(["TimeUS", *numbers, *texts])
        formats[name] = _Message(type_id, name, fmt, columns)
    return formats


def _format_record(message: _Message) -> bytes:
    return FMT.pack(message.type_id, message.length, message.name.encode(),
                    message.fmt.encode(), message.columns.encode())


def _pack(message: _Message, record: Record, time_us: int) -> bytes:
    values: dict[str, object] = dict(record.fields)
    values |= {name: text.encode() for name, text in record.where}
    if record.text is not None:
        values[record.text[0]] = record.text[1].encode()
    row: list[object] = [time_us]
    for column, code in zip(message.columns.split(",")[1:], message.fmt[1:], strict=True):
        value = values.get(column, b"" if code in "nNZ" else 0)
        if isinstance(value, bytes) and code not in "nNZ":     # a `where` on a number (I = 0)
            value = float(value)
        row.append(round(value) if code in "HB" else value)  # type: ignore[call-overload]
    return message.pack(*row)


def _armed(profile: Profile) -> Record | None:
    """The record that says the vehicle operates (armed) from boot, where the profile reads
    its operating time from one (ArduPilot logs ARM when the vehicle arms)."""
    source = family_sources(profile, "dataflash").signals.get(OPERATING)
    if source is None:
        return None
    raw = source.bits or next((r for r, meaning in source.values if meaning), 1)
    return Record(0, source.topic, ((source.field, float(raw)),), source.where)


def write_dataflash(dive: SimulatedDive, profile: Profile, path: Path) -> None:
    """TimeUS counts from boot, which is the dive's start."""
    formats = _formats(profile)
    with path.open("wb") as stream:
        for message in (FMT, *formats.values()):
            stream.write(_format_record(message))
        stream.write(formats["MSG"].pack(0, b"ArduSub V4.5.0 (auvdiag simulate)"))
        armed = _armed(profile)
        if armed is not None:
            stream.write(_pack(formats[armed.topic], armed, 0))
        for record in dive_records(dive, profile, "dataflash"):
            time_us = (record.time_ns - dive.start_ns) // 1000
            stream.write(_pack(formats[record.topic], record, time_us))
