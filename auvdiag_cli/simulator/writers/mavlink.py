"""MAVLink telemetry logs (.tlog) the way a ground station records an ArduSub vehicle:
each record is the receive time (big-endian µs since the Unix epoch) and a MAVLink 2 frame."""

import struct
from pathlib import Path

from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import COMMAND, FLOW, IMU, MARKER, dive_records

PWM_NEUTRAL_US, PWM_PER_COMMAND_US = 1500, 400
HEARTBEAT_PERIOD_NS = 1_000_000_000
MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_SEVERITY_INFO = 12, 3, 6


def command_to_pwm(command: float) -> int:
    """ArduSub output: 1500 µs neutral, ±400 µs at full command."""
    return round(PWM_NEUTRAL_US + PWM_PER_COMMAND_US * max(-1.0, min(1.0, command)))


def write_tlog(dive: SimulatedDive, path: Path) -> None:
    from pymavlink.dialects.v20 import ardupilotmega as mavlink

    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    boot_ns = dive.start_ns
    next_heartbeat = boot_ns
    with path.open("wb") as stream:

        def emit(time_ns: int, message: object) -> None:
            frame = message.pack(mav)  # type: ignore[attr-defined]
            stream.write(struct.pack(">Q", time_ns // 1000) + frame)

        for record in dive_records(dive):
            t_ns = record.time_ns
            boot_ms = (t_ns - boot_ns) // 1_000_000
            while next_heartbeat <= t_ns:
                emit(next_heartbeat, mav.heartbeat_encode(
                    MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0))
                next_heartbeat += HEARTBEAT_PERIOD_NS
            if record.kind == COMMAND:
                pwm = [command_to_pwm(c) for c in record.values]
                emit(t_ns, mav.servo_output_raw_encode(
                    (t_ns - boot_ns) // 1000 & 0xFFFFFFFF, 0, pwm[0], pwm[1], *[1500] * 6))
            elif record.kind == FLOW:
                emit(t_ns, mav.named_value_float_encode(boot_ms, b"FLOW", record.values[0]))
            elif record.kind == IMU:
                emit(t_ns, mav.attitude_encode(boot_ms, 0.0, 0.0, 0.0, 0.0, 0.0,
                                               record.values[0]))
            elif record.kind == MARKER:
                emit(t_ns, mav.statustext_encode(MAV_SEVERITY_INFO,
                                                 f"DMS {record.label}".encode()))
