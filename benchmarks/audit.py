"""Audit throughput: logs per minute through `auvdiag audit`, serial vs the local process
pool vs a Dask LocalCluster, and the peak memory of each worker.

Simulates --distinct one-hour dives of the Twin-Burger (16 x ZA, ZB, ZC and the paper's
mission; every other one with a fault from 30 min on) by two vehicles, launched under the
ROS namespaces /rovA and /rovB, writes them as standalone MCAP and copies them to --logs
files in one folder (a copy is a separate log to the audit: its own row, its own
diagnosis). The audit must find each log's vehicle from its namespace, and the trend must
go per vehicle. Each mode audits the folder from scratch into its own output folder, as a
fresh `auvdiag audit` process; the wall time includes starting the workers.

Usage: python benchmarks/audit.py [--logs 200] [--distinct 8] [--jobs 2] [--workdir DIR]
       [--modes serial,pool,dask] [--json results.json]
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

from bytecode import write_bytecode  # benchmarks/bytecode.py, beside this script

HOUR_REPEATS = 16
VEHICLES = ("/rovA", "/rovB")
FAULTS = [("thruster_0", "dead"), ("flow_sensor", "covered"), ("thruster_1", "dead"),
          ("yaw_rate_sensor", "dead")]


def make_fleet(folder: Path, logs: int, distinct: int) -> None:
    from auvdiag_cli import api
    from auvdiag_cli.simulator.faults import Fault
    from auvdiag_cli.simulator.run import LOG_EPOCH_NS
    from auvdiag_cli.simulator.scenarios import DMS_ALL, PAPER_MISSION, Scenario

    profile = api.load_profile()
    steps = (DMS_ALL + PAPER_MISSION) * HOUR_REPEATS
    sources = []
    for index in range(distinct):
        fault = Fault(*FAULTS[(index // 2) % len(FAULTS)], 1800.0) if index % 2 else None
        scenario = Scenario(f"hour-{index}", "one-hour dive", steps, fault,
                            run_after_fault_s=3600.0)
        path = folder / f"source-{index}.mcap"
        namespace = VEHICLES[(index // 2) % len(VEHICLES)]
        dive = api.simulate(scenario, profile, path, log_format="mcap", seed=100 + index,
                            start_ns=LOG_EPOCH_NS + index * 86_400 * 10**9,
                            namespace=namespace)
        sources.append((path, f"ros-{namespace[1:]}"))
        print(f"  simulated {path.name} ({dive.duration_s / 60:.0f} min, {namespace}, "
              f"fault: {fault.component if fault else 'none'})", file=sys.stderr, flush=True)
    fleet = folder / "fleet"
    fleet.mkdir()
    expected = {}
    for number in range(logs):
        source, vehicle = sources[number % distinct]
        shutil.copy(source, fleet / f"dive-{number:03d}.mcap")
        truth = json.loads(source.with_suffix(".truth.json").read_text())["expected"]
        expected[f"dive-{number:03d}.mcap"] = {"verdict": truth["verdict"],
                                               "vehicle": vehicle}
    (folder / "expected.json").write_text(json.dumps(expected, indent=1))


def run_audit(fleet: Path, output: Path, extra: list[str]) -> tuple[float, list[dict]]:
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "auvdiag_cli", "audit", str(fleet), "--output",
                    str(output), "--fail-on", "none", *extra], check=True,
                   stderr=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
    seconds = time.perf_counter() - started
    records = [json.loads(p.read_text()) for p in (output / "logs").glob("*.json")]
    return seconds, records


def _trend(output: Path) -> dict[str, int]:
    """The vehicles the trend of the audit's output tests, and over how many dives."""
    from auvdiag_cli import api

    trend = api.trend(output)
    return {**trend.short, **{t.vehicle: len(t.ratios) for t in trend.trends}}


def measure(fleet: Path, workdir: Path, mode: str, jobs: int) -> dict:
    output = workdir / f"out-{mode}"
    if mode == "dask":
        from distributed import LocalCluster

        with LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster:
            seconds, records = run_audit(fleet, output,
                                         ["--scheduler", cluster.scheduler_address])
    else:
        seconds, records = run_audit(fleet, output, ["--jobs", "1" if mode == "serial"
                                                     else str(jobs)])
    errors = [r for r in records if r.get("error")]
    expected = json.loads((workdir / "expected.json").read_text())
    wanted = [expected.get(Path(r["log"]).name, {}) for r in records]
    right = sum(r["verdict"] == w.get("verdict") for r, w in zip(records, wanted, strict=True))
    vehicles = sum(r["audit"]["vehicle"]["id"] == w.get("vehicle")
                   for r, w in zip(records, wanted, strict=True))
    return {"mode": mode, "workers": 1 if mode == "serial" else jobs, "logs": len(records),
            "errors": len(errors), "verdicts_as_simulated": right,
            "vehicles_as_simulated": vehicles, "trend": _trend(output),
            "seconds": round(seconds, 1),
            "logs_per_minute": round(60 * len(records) / seconds, 2),
            "diagnosis_s_median": round(sorted(r["audit"]["seconds"] for r in records)
                                        [len(records) // 2], 2),
            "peak_rss_mb_per_worker": max(r["audit"]["peak_rss_mb"] for r in records)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=200)
    parser.add_argument("--distinct", type=int, default=8)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--modes", default="serial,pool,dask")
    parser.add_argument("--workdir", type=Path)
    parser.add_argument("--json", type=Path, help="Also write the results here.")
    args = parser.parse_args()
    write_bytecode()          # as on an installed copy: no process compiles the sources
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="auvdiag-audit-bench-"))
    workdir.mkdir(parents=True, exist_ok=True)
    print(f"simulating {args.distinct} one-hour dives into {workdir}", file=sys.stderr,
          flush=True)
    if not (workdir / "fleet").is_dir():
        make_fleet(workdir, args.logs, args.distinct)
    elif not isinstance(next(iter(json.loads((workdir / "expected.json").read_text())
                                  .values()), None), dict):
        raise SystemExit(f"{workdir}: a fleet made by an older version of this benchmark "
                         "(no vehicles in expected.json); use a new --workdir")
    results = []
    for mode in args.modes.split(","):
        shutil.rmtree(workdir / f"out-{mode}", ignore_errors=True)
        result = measure(workdir / "fleet", workdir, mode, args.jobs)
        results.append(result)
        print(json.dumps(result), file=sys.stderr, flush=True)
    serial = next((r for r in results if r["mode"] == "serial"), None)
    print(f"Measured {date.today()} on {platform.machine()}, {os.cpu_count()} cores: "
          f"{args.logs} simulated dives of 61-90 min ({args.distinct} distinct, copied) by "
          f"{len(VEHICLES)} vehicles in one folder, standalone MCAP, shipped model.\n")
    print("| mode | workers | logs/min | speed-up vs serial | median s/log | peak RSS/worker "
          "| verdicts as simulated | vehicles as simulated | trend: dives per vehicle |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in results:
        ratio = (f"{r['logs_per_minute'] / serial['logs_per_minute']:.2f}x" if serial
                 else "-")
        print(f"| {r['mode']} | {r['workers']} | {r['logs_per_minute']:.1f} | {ratio} | "
              f"{r['diagnosis_s_median']:.1f} | {r['peak_rss_mb_per_worker']:.0f} MB | "
              f"{r['verdicts_as_simulated']}/{r['logs']} | "
              f"{r['vehicles_as_simulated']}/{r['logs']} | "
              f"{', '.join(f'{v} {n}' for v, n in sorted(r['trend'].items()))} |")
    if args.json:
        args.json.write_text(json.dumps({"date": str(date.today()), "machine":
                                         platform.machine(), "cores": os.cpu_count(),
                                         "logs": args.logs, "results": results}, indent=2))


if __name__ == "__main__":
    main()
