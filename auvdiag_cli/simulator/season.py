"""A simulated season for a fleet: each vehicle dives once a week; one of them has a
thruster that loses a little thrust every week. Test data for the fleet trend."""

from collections.abc import Sequence
from datetime import UTC, datetime, timedelta
from pathlib import Path

from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from auvdiag_cli.vehicle.profile import Profile

WEAK_SCENARIO = "mission-{thruster}-weak"
SEASON_START = datetime(2026, 3, 2, 9, 0, tzinfo=UTC)


def thrust_kept(week: int, loss_per_week: float) -> float:
    return max(0.0, 1.0 - loss_per_week * week)


def write_season(folder: Path, profile: Profile, vehicles: Sequence[str], wearing: str,
                 weeks: int, loss_per_week: float, thruster: str = "thruster_0",
                 fmt: str = "mcap", seed: int = 500) -> list[Path]:
    """Write ``folder/VEHICLE/week-NN.mcap`` for every vehicle and week; ``wearing``'s
    ``thruster`` keeps 1 − loss_per_week · week of its thrust from the first second of each
    dive, the other vehicles stay healthy. Returns the logs written."""
    name = WEAK_SCENARIO.format(thruster=thruster.replace("_", "-"))
    logs = []
    for number, vehicle in enumerate(vehicles):
        (folder / vehicle).mkdir(parents=True, exist_ok=True)
        for week in range(weeks):
            kept = thrust_kept(week, loss_per_week) if vehicle == wearing else 1.0
            scenario = get_scenario(name, profile, 0.0, severity=kept)
            start = SEASON_START + timedelta(weeks=week, hours=number)
            dive = simulate(scenario, profile, seed + 100 * number + week,
                            round(start.timestamp() * 1e9))
            path = folder / vehicle / f"week-{week:02d}.{fmt}"
            write_log(dive, profile, path, fmt)
            logs.append(path)
    return logs
