"""ArduPilot DataFlash logs (.bin). pymavlink reads them but has no writer, so the records are
packed here: every record is ``A3 95 <type>`` and a little-endian payload described by an
FMT record (type 128) earlier in the file."""

import struct
from pathlib import Path

from adapters.signals import OPERATING
from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import (
    Record,
    dive_records,
    family_sources,
    operating_raw,
)
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
    "PARM": ("QNf", "TimeUS,Name,Value"),
}
FIRST_TYPE_ID = 34


def _formats(profile: Profile) -> dict[str, _Message]:
    """One record format per message name the profile reads, plus MSG for the banner and
    PARM for the parameters."""
    sources = family_sources(profile, "dataflash")
    fields: dict[str, list[str]] = {"MSG": [], "PARM": []}
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
    return Record(0, source.topic, ((source.field, operating_raw(source)),), source.where)


def write_dataflash(dive: SimulatedDive, profile: Profile, path: Path) -> None:
    """TimeUS counts from boot, which is the dive's start."""
    formats = _formats(profile)
    with path.open("wb") as stream:
        for message in (FMT, *formats.values()):
            stream.write(_format_record(message))
        for text in _banner(profile):
            stream.write(formats["MSG"].pack(0, text.encode()))
        for name, value in _parameters(profile):
            stream.write(formats["PARM"].pack(0, name.encode(), value))
        armed = _armed(profile)
        if armed is not None:
            stream.write(_pack(formats[armed.topic], armed, 0))
        for record in dive_records(dive, profile, "dataflash"):
            time_us = (record.time_ns - dive.start_ns) // 1000
            stream.write(_pack(formats[record.topic], record, time_us))



FRAMES = {3: "TRI", 4: "QUAD/X", 6: "HEXA/X", 8: "OCTA/X"}


def _motors(profile: Profile) -> list[tuple[int, float, float, str]]:
    """(output number, scale, offset, kind) of each rotor or thruster the profile reads
    from RCOU, in the profile's order: ArduPilot's motor 1, 2 …"""
    sources = family_sources(profile, "dataflash").signals
    found = []
    for command in profile.effort_actuators:
        source = sources.get(command.name)
        if command.kind in ("rotor", "thruster") and source is not None and \
                source.topic == "RCOU" and source.field[1:].isdigit():
            found.append((int(source.field[1:]), source.scale, source.offset, command.kind))
    return found


def _banner(profile: Profile) -> list[str]:
    """What the firmware writes first: its name (a vehicle with rotors flies ArduCopter,
    one with control surfaces ArduPlane, else ArduSub) and a multirotor's frame."""
    kinds = {c.kind for c in profile.effort_actuators}
    rotors = sum(kind == "rotor" for *_, kind in _motors(profile))
    if "rotor" in kinds:
        return ["ArduCopter V4.5.0 (auvdiag simulate)",
                *([f"Frame: {FRAMES[rotors]}"] if rotors in FRAMES else [])]
    if kinds & {"control_surface", "engine"}:
        return ["ArduPlane V4.5.0 (auvdiag simulate)"]
    return ["ArduSub V4.5.0 (auvdiag simulate)"]


def _parameters(profile: Profile) -> list[tuple[str, float]]:
    """The parameters that say which output drives which motor (SERVOn_FUNCTION 33 is motor
    1) and the PWM range the profile's map gives the motors (MOT_PWM_MIN/MAX: command 0 …
    1 of a rotor, -1 … 1 of a thruster)."""
    motors = _motors(profile)
    parameters: list[tuple[str, float]] = [
        (f"SERVO{output}_FUNCTION", 33.0 + number) for number, (output, *_) in
        enumerate(motors)]
    if motors:
        _, scale, offset, kind = motors[0]
        low = (0.0 if kind == "rotor" else -1.0)
        parameters += [("MOT_PWM_MIN", round((low - offset) / scale)),
                       ("MOT_PWM_MAX", round((1.0 - offset) / scale))]
    return parameters
