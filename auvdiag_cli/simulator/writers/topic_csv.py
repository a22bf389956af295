"""A ROS 1 bag exported as a folder of per-topic CSVs, as ``rostopic echo -b BAG -p TOPIC``
writes them: ``%time`` (the bag's record time, ns), then ``field.<path>`` for every field,
arrays flattened by index (``field.data0``), a stamp as one integer of ns. The bag is written
first by rosbags (`write_rosbag`), then read back message by message and flattened."""

import csv
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.ros import ExtraTopic, write_rosbag
from auvdiag_cli.vehicle.profile import Profile


def _flattened(value: Any, prefix: str) -> Iterator[tuple[str, Any]]:
    """(column, cell) pairs of one message, in its fields' order."""
    if hasattr(value, "sec") and hasattr(value, "nanosec"):
        yield prefix, value.sec * 1_000_000_000 + value.nanosec
    elif hasattr(value, "__dataclass_fields__"):
        for name in value.__dataclass_fields__:
            if name != "__msgtype__":
                yield from _flattened(getattr(value, name), f"{prefix}.{name}")
    elif isinstance(value, (list, tuple, np.ndarray)):
        for index, item in enumerate(value):
            yield from _flattened(item, f"{prefix}{index}")
    elif isinstance(value, (bool, np.bool_)):
        yield prefix, int(value)             # rostopic echo -p writes a flag as 1 or 0
    else:
        yield prefix, value


def export_topic_csvs(bag: Path, folder: Path) -> None:
    """Every topic of the ROS 1 ``bag`` as ``folder/<folder name>-<topic>.csv``, each message
    decoded by the definition the bag carries (as `rostopic echo -p` does)."""
    from rosbags.highlevel import AnyReader

    folder.mkdir(parents=True)
    with AnyReader([bag]) as reader:
        for connection in reader.connections:
            name = connection.topic.strip("/").replace("/", "-")
            with (folder / f"{folder.name}-{name}.csv").open("w", newline="") as stream:
                out = csv.writer(stream)
                header_written = False
                for _, time_ns, raw in reader.messages(connections=[connection]):
                    message = reader.deserialize(raw, connection.msgtype)
                    cells = list(_flattened(message, "field"))
                    if not header_written:
                        out.writerow(["%time", *(column for column, _ in cells)])
                        header_written = True
                    out.writerow([time_ns, *(cell for _, cell in cells)])


def write_topic_csvs(dive: SimulatedDive, profile: Profile, folder: Path,
                     extra: tuple[ExtraTopic, ...] = ()) -> None:
    """``dive`` as the per-topic CSV export of the ROS 1 bag it would have been."""
    with tempfile.TemporaryDirectory() as scratch:
        bag = Path(scratch) / f"{folder.name}.bag"
        write_rosbag(dive, profile, bag, "bag", extra)
        export_topic_csvs(bag, folder)
