"""MAVLink telemetry logs (.tlog) the way a ground station records an ArduSub vehicle, laid
out by the profile's `[sources.mavlink]` table: each record is the receive time (big-endian
µs since the Unix epoch) and a MAVLink 2 frame; a heartbeat every second, of the vehicle
type and armed flag the profile's operating source reads (a submarine, disarmed, without
one)."""

import struct
from pathlib import Path
from typing import Any

from adapters.signals import OPERATING
from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import Record, dive_records, family_sources
from auvdiag_cli.vehicle.profile import Profile

HEARTBEAT_PERIOD_NS = 1_000_000_000
MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_SEVERITY_INFO = 12, 3, 6


def mavlink_message(dialect: Any, record: Record, boot_ns: int) -> Any:
    """The record as a pymavlink message: every field zero except the boot-relative time
    fields, the record's fields (integers rounded, as PWM is) and its ``where`` fields."""
    cls = getattr(dialect, f"MAVLink_{record.topic.lower()}_message", None)
    if cls is None:
        raise ValueError(f"cannot write {record.topic}: not a MAVLink message")
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
    types = dict(zip(cls.fieldnames, cls.fieldtypes, strict=True))

    def zero(name: str) -> Any:
        if types[name] == "char":
            return b""
        return [0] * lengths[name] if lengths[name] else 0

    values = {name: zero(name) for name in cls.fieldnames}
    since_boot_ns = record.time_ns - boot_ns
    times = {"time_boot_ms": since_boot_ns // 1_000_000 & 0xFFFFFFFF,
             "time_usec": since_boot_ns // 1000 & 0xFFFFFFFF}
    values |= {name: t for name, t in times.items() if name in values}
    for name, raw in record.fields:
        values[name] = round(float(raw)) if types[name].startswith(("int", "uint")) else raw
    for name, text in record.where:
        values[name] = text.encode()
    if record.text is not None:
        values[record.text[0]] = record.text[1].encode()
        values["severity"] = MAV_SEVERITY_INFO
    return cls(**values)


def _heartbeat_identity(profile: Profile) -> tuple[int, int]:
    """(vehicle type, base mode) of the heartbeat: armed the whole dive when the profile reads
    its operating time from the heartbeat."""
    source = family_sources(profile, "mavlink").signals.get(OPERATING)
    if source is None or source.topic != "HEARTBEAT":
        return MAV_TYPE_SUBMARINE, 0
    where = dict(source.where)
    return int(where.get("type", MAV_TYPE_SUBMARINE)), source.bits


def write_tlog(dive: SimulatedDive, profile: Profile, path: Path) -> None:
    from pymavlink.dialects.v20 import ardupilotmega as mavlink

    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    vehicle_type, base_mode = _heartbeat_identity(profile)
    boot_ns = dive.start_ns
    next_heartbeat = boot_ns
    with path.open("wb") as stream:

        def emit(time_ns: int, message: Any) -> None:
            stream.write(struct.pack(">Q", time_ns // 1000) + message.pack(mav))

        for record in dive_records(dive, profile, "mavlink"):
            while next_heartbeat <= record.time_ns:
                emit(next_heartbeat, mav.heartbeat_encode(
                    vehicle_type, MAV_AUTOPILOT_ARDUPILOTMEGA, base_mode, 0, 0))
                next_heartbeat += HEARTBEAT_PERIOD_NS
            emit(record.time_ns, mavlink_message(mavlink, record, boot_ns))
