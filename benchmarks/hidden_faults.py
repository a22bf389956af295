"""Faults a controller hides: detection and naming of one thruster weakened to 50-90 % of
its thrust while the vehicle's controller holds heading, speed and depth, on the simulated
vehicles with their shipped models; and false alarms on normal missions.

Each weakened dive is the paper's mission with the thruster weakened from 60 s (the
simulator's `mission-<thruster>-weak` scenario at the given thrust fraction). A fault is
detected when the verdict is a fault; "by the motion" counts dives where the model's replay
raised a bit (what the diagnosis found before the command relations), "by the commands
alone" those where only the commands departed from the motion; "named"
is the verdict's component being the weakened thruster; "named in a group" is that
thruster being among the candidates named together (thrusters that act alike).

Usage: python benchmarks/hidden_faults.py [--seeds 3] [--jobs 2] > hidden_faults.md
"""

import argparse
import os
import platform
import tempfile
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from datetime import date
from pathlib import Path

VEHICLES = {"twin_burger": "ros2-mcap", "three_thruster": "ros2-mcap", "bluerov2": "tlog"}
FRACTIONS = (0.5, 0.6, 0.7, 0.8, 0.9)
NORMAL = ("paper-normal", "mission-ccw", "mission-large-cw", "mission-sprint-ccw",
          "mission-fast-cw")
FIRST_SEED = 401


def _run(job: tuple[str, str, str, int, float | None]) -> dict[str, object]:
    from auvdiag_cli import api
    from auvdiag_cli.simulator.scenarios import get_scenario

    vehicle, scenario_name, truth, seed, fraction = job
    profile = api.load_profile(vehicle)
    scenario = get_scenario(scenario_name, profile, severity=fraction)
    with tempfile.TemporaryDirectory() as work:
        log = Path(work) / "dive"
        api.simulate(scenario, profile, log, log_format=VEHICLES[vehicle], seed=seed)
        d = api.diagnose(log, profile, api.load_model(profile=profile))
    check = d.command_check
    return {"vehicle": vehicle, "truth": truth, "fraction": fraction, "fault": d.verdict == "fault",
            "by_motion": any(d.b.values()),
            "by_commands": check is not None and check.alarm_s is not None
            and not any(d.b.values()),
            "named": d.component == truth, "in_group": truth in d.candidates}


def _jobs(seeds: int) -> list[tuple[str, str, str, int, float | None]]:
    from auvdiag_cli import api

    jobs: list[tuple[str, str, str, int, float | None]] = []
    for vehicle in VEHICLES:
        for command in api.load_profile(vehicle).commands:
            thruster = command.component
            jobs += [(vehicle, f"mission-{thruster.replace('_', '-')}-weak", thruster, seed,
                      fraction) for fraction in FRACTIONS
                     for seed in range(FIRST_SEED, FIRST_SEED + seeds)]
        jobs += [(vehicle, scenario, "", seed, None) for scenario in NORMAL
                 for seed in range(FIRST_SEED, FIRST_SEED + seeds)]
    return jobs


def _percent(part: int, whole: int) -> str:
    return f"{part / whole:.0%}" if whole else "-"


def _table(results: list[dict[str, object]]) -> list[str]:
    lines = []
    for vehicle in VEHICLES:
        mine = [r for r in results if r["vehicle"] == vehicle]
        normal = [r for r in mine if r["fraction"] is None]
        faulty = defaultdict(list)
        for r in mine:
            if r["fraction"] is not None:
                faulty[r["fraction"]].append(r)
        lines += ["", f"**{vehicle}** ({len({r['truth'] for r in mine if r['truth']})} thrusters; "
                      f"false alarms on {len(normal)} normal missions: "
                      f"{sum(bool(r['fault']) for r in normal)})", "",
                  "| thrust kept | dives | detected | by the motion | by the commands alone | "
                  "named exactly | named in a group |", "|---|---|---|---|---|---|---|"]
        for fraction in FRACTIONS:
            rows = faulty[fraction]
            count = len(rows)
            lines.append(f"| {fraction:.0%} | {count} | "
                         f"{_percent(sum(bool(r['fault']) for r in rows), count)} | "
                         f"{_percent(sum(bool(r['by_motion']) for r in rows), count)} | "
                         f"{_percent(sum(bool(r['by_commands']) for r in rows), count)} | "
                         f"{_percent(sum(bool(r['named']) for r in rows), count)} | "
                         f"{_percent(sum(bool(r['in_group']) for r in rows), count)} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    jobs = _jobs(args.seeds)
    started = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(pool.map(_run, jobs, chunksize=4))
    minutes = (time.perf_counter() - started) / 60
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), Python "
          f"{platform.python_version()}: {len(jobs)} simulated dives (seeds {FIRST_SEED}-"
          f"{FIRST_SEED + args.seeds - 1}) diagnosed with the shipped models in "
          f"{minutes:.1f} min.")
    print("\n".join(_table(results)))


if __name__ == "__main__":
    main()
