"""A simulated dive as one time-ordered stream of records, whatever the output format."""

from collections.abc import Iterator
from dataclasses import dataclass

from auvdiag_cli.simulator.run import SimulatedDive

COMMAND, FLOW, IMU, MARKER = "command", "flow", "imu", "marker"


@dataclass(frozen=True)
class Record:
    time_ns: int                     # receive time, the log's clock
    kind: str                        # COMMAND, FLOW, IMU or MARKER
    values: tuple[float, ...]        # thruster commands, flow m/s, yaw rate rad/s
    label: str = ""                  # marker text


def dive_records(dive: SimulatedDive) -> Iterator[Record]:
    """Every message of the dive in receive-time order."""
    records = [Record(dive.start_ns + round(t * 1e9), kind, v)
               for kind, stream in ((COMMAND, dive.commands), (FLOW, dive.flow), (IMU, dive.imu))
               for t, v in zip(stream.times_s, stream.values, strict=True)]
    records += [Record(dive.start_ns + round(t * 1e9), MARKER, (), label)
                for t, label in dive.markers]
    records.sort(key=lambda record: record.time_ns)
    yield from records
