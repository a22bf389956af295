"""What an ArduPilot log says of the vehicle that wrote it: its firmware (a copter, a plane,
a sub, a rover), its frame, and the parameters it logged (which servo output drives which
motor or surface, the motors' PWM range). A DataFlash log writes its firmware banner
(MSG "ArduCopter V4.5.7 (…)", "Frame: QUAD/X") and every parameter (PARM) as it begins; a
telemetry log carries the autopilot's HEARTBEAT (its MAV_TYPE), and the parameters and the
banner where a ground station fetched them (PARAM_VALUE, STATUSTEXT). Nothing here raises
on a damaged log: what cannot be read says nothing."""

import struct
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from adapters.mavlink_scan import (
    TLOG_TIME_LENGTH,
    RecordIndex,
    index_dataflash,
    index_tlog,
    tlog_frame_fields,
)

# The banner and the parameters come first; a log's first megabytes hold them.
PREFIX_BYTES = 8 << 20
HEARTBEAT, PARAM_VALUE, STATUSTEXT = 0, 22, 253
AUTOPILOT_INVALID = 8            # MAV_AUTOPILOT_INVALID: a ground station, not a vehicle
HEARTBEAT_LENGTH, PARAM_VALUE_LENGTH, STATUSTEXT_LENGTH = 6, 25, 51   # what is read of each
DATAFLASH_NAME, DATAFLASH_TEXT = 16, 64        # PARM's Name ('N'), MSG's Message ('Z')

# The firmware's name as its banner starts -> the kind of vehicle.
FIRMWARE_VEHICLES = (("ArduCopter", "copter"), ("APM:Copter", "copter"),
                     ("ArduPlane", "plane"), ("APM:Plane", "plane"),
                     ("ArduSub", "sub"), ("ArduRover", "rover"), ("APM:Rover", "rover"),
                     ("Rover", "rover"))
# MAV_TYPE -> (kind of vehicle, its motors where the type says how many).
MAV_TYPES = {1: ("plane", None), 2: ("copter", 4), 3: ("copter", 2), 4: ("copter", None),
             10: ("rover", None), 11: ("rover", None), 12: ("sub", None), 13: ("copter", 6),
             14: ("copter", 8), 15: ("copter", 3), 19: ("plane", None), 20: ("plane", None),
             21: ("plane", None), 22: ("plane", None)}
# A multirotor's frame as ArduCopter's banner names it -> its motors.
FRAME_MOTORS = {"TRI": 3, "QUAD": 4, "HEXA": 6, "Y6": 6, "OCTA": 8, "OCTAQUAD": 8, "DODECA": 12}


@dataclass(frozen=True)
class AutopilotSetup:
    vehicle: str | None                  # "copter", "plane", "sub", "rover"; None: unknown
    evidence: str                        # where in the log it was read
    frame: str | None = None             # "QUAD/X", from the banner
    motors: int | None = None            # a multirotor's motors, from its frame or type
    parameters: dict[str, float] = field(default_factory=dict)

    def parameter(self, name: str) -> float | None:
        return self.parameters.get(name)


def autopilot_setup(path: Path, family: str) -> AutopilotSetup | None:
    """The setup an ArduPilot DataFlash (``family`` "dataflash") or telemetry ("mavlink")
    log states; None where it states none."""
    if family not in ("dataflash", "mavlink"):
        return None
    try:
        with path.open("rb") as stream:
            prefix = stream.read(PREFIX_BYTES)
        if family == "dataflash":
            index = index_dataflash(prefix)
            texts, parameters = _dataflash_texts(index), dataflash_parameters(index)
            mav_type = None
        else:
            index = index_tlog(prefix, {})
            texts, parameters, mav_type = _tlog_contents(index)
    except (OSError, ValueError, IndexError, struct.error):
        return None
    return _setup(texts, parameters, mav_type)


def _setup(texts: list[str], parameters: dict[str, float], mav_type: int | None
           ) -> AutopilotSetup | None:
    banner = next((t for t in texts for name, _ in FIRMWARE_VEHICLES if t.startswith(name)),
                  None)
    frame = next((t.split(":", 1)[1].strip() for t in texts if t.startswith("Frame:")), None)
    by_frame = FRAME_MOTORS.get((frame or "").split("/", 1)[0].split(" ", 1)[0].upper())
    vehicle, by_type = MAV_TYPES.get(mav_type, (None, None)) if mav_type is not None \
        else (None, None)
    evidence = [f"HEARTBEAT MAV_TYPE {mav_type}"] if vehicle else []
    if banner is not None:
        vehicle = next(kind for name, kind in FIRMWARE_VEHICLES if banner.startswith(name))
        evidence.insert(0, f'"{banner}"')
    if frame is not None:
        evidence.append(f'"Frame: {frame}"')
    if parameters:
        evidence.append(f"{len(parameters)} parameters")
    if vehicle is None and not parameters:
        return None
    return AutopilotSetup(vehicle, ", ".join(evidence), frame, by_frame or by_type, parameters)


def text_of(raw: bytes) -> str:
    return raw.split(b"\0", 1)[0].decode("utf-8", "replace").strip()


def dataflash_records(index: RecordIndex, name: str, types: str) -> list[tuple[int, bytes]]:
    """(time in µs or `NO_TIME`/`BAD_TIME`, the payload after the time word) of every record
    of ``name`` whose format starts with ``types`` (a 64-bit time first), in file order."""
    found = [t for t, f in index.formats.items() if f.name == name and f.types.startswith(types)]
    positions = np.sort(np.concatenate([index.of_type(t) for t in found] or
                                       [np.zeros(0, np.int64)]))
    records = []
    for position in positions:
        start = int(index.offsets[position])
        length = index.formats[int(index.type_ids[position])].length
        records.append((int(index.times_us[position]),
                        bytes(index.data[start + 3 + 8:start + length])))
    return records


def _dataflash_texts(index: RecordIndex) -> list[str]:
    return [dataflash_text(p) for _, p in dataflash_records(index, "MSG", "QZ")]


def dataflash_text(payload: bytes) -> str:
    """A MSG record's text."""
    return text_of(payload[:DATAFLASH_TEXT])


def dataflash_parameters(index: RecordIndex) -> dict[str, float]:
    """Every parameter a DataFlash log wrote (PARM), by name."""
    parameters = {}
    for _, payload in dataflash_records(index, "PARM", "QNf"):
        (value,) = struct.unpack_from("<f", payload, DATAFLASH_NAME)
        if np.isfinite(value):
            parameters[text_of(payload[:DATAFLASH_NAME])] = float(value)
    return parameters


class TlogPayloads:
    """A telemetry log's frames, their payloads read by message id."""

    def __init__(self, index: RecordIndex) -> None:
        self.data = index.data
        version, self.msgid, self.starts, self.lengths = tlog_frame_fields(index.data,
                                                                           index.offsets)
        frames = index.offsets + TLOG_TIME_LENGTH
        self.sysids = np.where(version == 2, self.data[frames + 5],
                               self.data[frames + 3]).astype(int)
        self.times_us = index.times_us

    def of(self, msgid: int, size: int) -> list[tuple[int, bytes]]:
        """(system id, payload padded to ``size``: MAVLink 2 drops trailing zeros) of every
        frame of ``msgid``."""
        return [(int(self.sysids[k]), bytes(self.data[self.starts[k]:self.starts[k] + min(
            int(self.lengths[k]), size)]).ljust(size, b"\0"))
            for k in np.flatnonzero(self.msgid == msgid)]

    def times_of(self, msgid: int) -> list[int]:
        """The receive time (µs, or `BAD_TIME`) of every frame of ``msgid``, as `of` lists
        them."""
        return [int(t) for t in self.times_us[self.msgid == msgid]]


def autopilot_heartbeats(index: RecordIndex) -> Counter[tuple[int, int]]:
    """How many HEARTBEATs each (system id, MAV_TYPE) sent, of vehicles: a ground station's,
    a companion's or a camera's say MAV_AUTOPILOT_INVALID."""
    return Counter((sysid, payload[4]) for sysid, payload in TlogPayloads(index).of(
        HEARTBEAT, HEARTBEAT_LENGTH) if payload[5] != AUTOPILOT_INVALID)


def _tlog_contents(index: RecordIndex) -> tuple[list[str], dict[str, float], int | None]:
    """(STATUSTEXT texts, PARAM_VALUE parameters, the autopilot's MAV_TYPE)."""
    frames = TlogPayloads(index)
    texts = [text_of(raw[1:]) for _, raw in frames.of(STATUSTEXT, STATUSTEXT_LENGTH)]
    parameters = {}
    for _, raw in frames.of(PARAM_VALUE, PARAM_VALUE_LENGTH):
        (value,) = struct.unpack_from("<f", raw)
        if np.isfinite(value):
            parameters[text_of(raw[8:24])] = float(value)
    heard = autopilot_heartbeats(index)
    types: Counter[int] = Counter()
    for (_, mav_type), count in heard.items():
        types[mav_type] += count
    return texts, parameters, types.most_common(1)[0][0] if types else None
