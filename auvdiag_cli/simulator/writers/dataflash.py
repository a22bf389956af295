"""ArduPilot DataFlash logs (.bin). pymavlink reads them but has no writer, so the records are
packed here: every record is ``A3 95 <type>`` and a little-endian payload described by an
FMT record (type 128) earlier in the file."""

import struct
from pathlib import Path

from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.mavlink import command_to_pwm
from auvdiag_cli.simulator.writers.records import COMMAND, FLOW, IMU, MARKER, dive_records

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
RCOU = _Message(34, "RCOU", "Q" + "H" * 14, "TimeUS," + ",".join(f"C{i}" for i in range(1, 15)))
IMU_MSG = _Message(35, "IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ")
FLOW_MSG = _Message(36, "FLOW", "Qf", "TimeUS,Vel")
MSG = _Message(37, "MSG", "QZ", "TimeUS,Message")


def _format_record(message: _Message) -> bytes:
    return FMT.pack(message.type_id, message.length, message.name.encode(),
                    message.fmt.encode(), message.columns.encode())


def write_dataflash(dive: SimulatedDive, path: Path) -> None:
    """TimeUS counts from boot, which is the dive's start."""
    with path.open("wb") as stream:
        for message in (FMT, RCOU, IMU_MSG, FLOW_MSG, MSG):
            stream.write(_format_record(message))
        stream.write(MSG.pack(0, b"ArduSub V4.5.0 (auvdiag simulate)"))
        for record in dive_records(dive):
            time_us = (record.time_ns - dive.start_ns) // 1000
            if record.kind == COMMAND:
                pwm = [command_to_pwm(c) for c in record.values]
                stream.write(RCOU.pack(time_us, pwm[0], pwm[1], *[1500] * 12))
            elif record.kind == FLOW:
                stream.write(FLOW_MSG.pack(time_us, record.values[0]))
            elif record.kind == IMU:
                stream.write(IMU_MSG.pack(time_us, 0, 0.0, 0.0, record.values[0], 0.0, 0.0,
                                          -9.81))
            elif record.kind == MARKER:
                stream.write(MSG.pack(time_us, f"DMS {record.label}".encode()))
