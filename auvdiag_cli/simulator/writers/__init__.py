"""Write a simulated dive as a real log in any supported format, with its truth beside it."""

import json
import shutil
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from auvdiag_cli.engine.missions import mission_path
from auvdiag_cli.simulator.run import SimulatedDive, fault_summary
from auvdiag_cli.simulator.truth_files import truth_paths
from auvdiag_cli.simulator.writers.alog import write_alog
from auvdiag_cli.simulator.writers.csv_log import write_csv
from auvdiag_cli.simulator.writers.dataflash import write_dataflash
from auvdiag_cli.simulator.writers.mavlink import write_tlog
from auvdiag_cli.simulator.writers.records import first_message_s
from auvdiag_cli.simulator.writers.ros import ExtraTopic, write_mcap, write_rosbag
from auvdiag_cli.simulator.writers.topic_csv import write_topic_csvs
from auvdiag_cli.simulator.writers.ulog import write_ulog
from auvdiag_cli.vehicle.profile import Profile

__all__ = ["LOG_FORMATS", "ROS1_FORMATS", "ExtraTopic", "write_log"]

LOG_FORMATS = ("bag", "db3", "ros2-mcap", "mcap", "json-mcap", "protobuf-mcap", "tlog", "bin",
               "ulog", "alog", "csv", "topic-csv")
# A standalone MCAP's message encoding, by format.
_MCAP_ENCODINGS = {"mcap": "cdr", "json-mcap": "json", "protobuf-mcap": "protobuf"}
# Whose messages are ROS 1's (a per-topic CSV folder: `rostopic echo -p` of a ROS 1 bag):
# extra topics for them are built with ROS 1's types.
ROS1_FORMATS = ("bag", "topic-csv")


def write_log(dive: SimulatedDive, profile: Profile, path: Path, fmt: str,
              extra: Sequence[ExtraTopic] = (), namespace: str = "") -> None:
    """Write ``dive`` to ``path`` in format ``fmt`` and its truth beside it; ``extra`` adds
    unrelated topics to the ROS formats (MAVLink logs have no place for them), and
    ``namespace`` puts the profile's ROS topics under a namespace, as a vehicle launched
    under it publishes them."""
    if fmt not in LOG_FORMATS:
        raise ValueError(f"unknown log format {fmt!r} (writable: {', '.join(LOG_FORMATS)})")
    if path.exists():
        raise FileExistsError(f"{path}: exists already, not overwriting")
    if namespace and "ros" in profile.sources:
        profile = replace(profile, sources={
            **profile.sources, "ros": profile.sources["ros"].moved_under(namespace)})
    try:
        _write(dive, profile, path, fmt, extra)
    except BaseException:
        # A log cut short by a failure would read as damaged and block the next try.
        if path.is_dir():
            shutil.rmtree(path)
        path.unlink(missing_ok=True)
        raise
    _write_truth(dive, path, fmt)


def _write(dive: SimulatedDive, profile: Profile, path: Path, fmt: str,
           extra: Sequence[ExtraTopic]) -> None:
    if fmt in ("bag", "db3", "ros2-mcap"):
        write_rosbag(dive, profile, path, fmt, extra)
    elif fmt in _MCAP_ENCODINGS:
        write_mcap(dive, profile, path, extra, _MCAP_ENCODINGS[fmt])
    elif fmt == "tlog":
        write_tlog(dive, profile, path)
    elif fmt == "csv":
        write_csv(dive, profile, path)
    elif fmt == "topic-csv":
        write_topic_csvs(dive, profile, path, tuple(extra))
    elif fmt == "ulog":
        write_ulog(dive, profile, path)
    elif fmt == "alog":
        write_alog(dive, profile, path)
    else:
        write_dataflash(dive, profile, path)


def _write_truth(dive: SimulatedDive, path: Path, fmt: str) -> None:
    json_path, csv_path = truth_paths(path)
    fault = dive.scenario.fault
    # Report times count from the log's first message, which carries receive jitter.
    first_s = first_message_s(dive)
    fault_info = fault_summary(fault)
    if fault_info is not None:
        fault_info["onset_s"] = round(float(fault_info["onset_s"]) - first_s, 6)  # type: ignore[arg-type]
    truth = {
        "log": path.name,
        "format": fmt,
        "scenario": dive.scenario.name,
        "description": dive.scenario.description,
        "seed": dive.seed,
        "duration_s": round(dive.duration_s, 3),
        "fault": fault_info,
        "expected": {
            "verdict": "normal" if fault is None else "fault",
            "component": None if fault is None else fault.component,
        },
        "phases": [{"name": name, "start_s": round(t, 3)} for name, t in dive.phase_starts_s],
        "truth_series": csv_path.name,
    }
    json_path.write_text(json.dumps(truth, indent=2) + "\n", encoding="utf-8")
    dive.truth.round(6).to_csv(csv_path, index=False)
    if dive.missions:
        plans = [{**leg, "start_s": round(float(leg["start_s"]) - first_s, 6)}  # type: ignore[arg-type]
                 for leg in dive.missions]
        mission_path(path).write_text(json.dumps({"missions": plans}, indent=2) + "\n",
                                      encoding="utf-8")
