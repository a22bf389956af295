"""The mission plan beside a log, ``NAME.mission.json`` (as the simulator writes it, and a
mission planner may too): the legs the closed-loop replay of Substituting Control flies."""

import json
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class MissionLeg:
    start_s: float                              # from the log's first message
    waypoints: tuple[tuple[float, float], ...]  # metres, the leg's navigation frame
    cruise_speed_mps: float | None = None
    depths_m: tuple[float, ...] = ()


def mission_path(log_path: Path) -> Path:
    return log_path.with_name(log_path.name.split(".")[0] + ".mission.json")


def read_missions(path: Path) -> tuple[MissionLeg, ...]:
    """Mission legs: ``start_s`` (from the log's first message), ``waypoints`` [[x, y], …]
    in metres in the vehicle's navigation frame (origin and heading at the leg's start),
    and optionally ``cruise_speed_mps`` and ``depths_m`` (raises ValueError or TypeError
    where the file says otherwise)."""
    data = json.loads(path.read_text(encoding="utf-8"))
    legs = data.get("missions") if isinstance(data, dict) else None
    if not isinstance(legs, list) or not all(
            isinstance(leg, dict) and "start_s" in leg and "waypoints" in leg for leg in legs):
        raise ValueError(f"{path}: expected {{\"missions\": [{{\"start_s\": …, "
                         "\"waypoints\": [[x, y], …]}, …]}")
    return tuple(MissionLeg(float(leg["start_s"]),
                            tuple((float(x), float(y)) for x, y in leg["waypoints"]),
                            None if leg.get("cruise_speed_mps") is None
                            else float(leg["cruise_speed_mps"]),
                            tuple(float(d) for d in leg.get("depths_m", [])))
                 for leg in legs)
