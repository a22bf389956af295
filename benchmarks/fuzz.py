"""Fuzzing campaign: every format's readers against damaged logs, as Markdown for the docs.

Writes one short simulated dive in every format (bag, db3, ros2-mcap, mcap, tlog, bin), damages
each --cases times (bit flips, random runs, 2/4/8-byte length or count fields set to huge, zero
or negative values, truncation, duplicated, deleted and swapped blocks), and runs every case
through `inspect`, `init-profile` and `diagnose` in a forked child with a time limit (20 s)
and an address-space limit (1 GiB above the fuzzer's own). Real ArduSub logs from
../shared/data/ardusub (when that folder is there) are damaged too, --real-cases times each.

Usage: python benchmarks/fuzz.py [--cases 10000] [--real-cases 2000] [--jobs N]
                                 [--json fuzz.json]
Exit status 1 when any case is a defect (crash, hang, memory, printed output); the defect cases
are in the JSON with their seed log, case number and mutations, to be replayed with
`python -m auvdiag_cli.fuzz --formats FMT --first-case N --cases 1`.
"""

import argparse
import contextlib
import json
import os
import platform
import sys
import tempfile
from datetime import date
from pathlib import Path

REAL_LOGS = Path(__file__).resolve().parents[2] / "shared" / "data" / "ardusub"


def _campaign(arguments: list[str], target: Path) -> dict[str, object]:
    """One campaign; its progress lines go to stderr, the Markdown alone to stdout."""
    from auvdiag_cli.fuzz.__main__ import main

    with contextlib.redirect_stdout(sys.stderr):
        main([*arguments, "--json", str(target)])
    return json.loads(target.read_text())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=10_000)
    parser.add_argument("--real-cases", type=int, default=2_000)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--json", type=Path)
    options = parser.parse_args()
    jobs = ["--jobs", str(options.jobs)]
    with tempfile.TemporaryDirectory() as folder:
        simulated = _campaign(["--cases", str(options.cases), *jobs], Path(folder) / "sim.json")
        seeds = dict(simulated["seeds"])  # type: ignore[call-overload]
        seconds = float(simulated["seconds"])  # type: ignore[arg-type]
        real = sorted(REAL_LOGS.glob("*")) if REAL_LOGS.is_dir() else []
        if real and options.real_cases:
            arguments = ["--formats", "", "--cases", str(options.real_cases), *jobs]
            for log in real:
                arguments += ["--seed-log", str(log)]
            field = _campaign(arguments, Path(folder) / "real.json")
            seeds |= {f"{name} (real ArduSub)": summary
                      for name, summary in field["seeds"].items()}  # type: ignore[attr-defined]
            seconds += float(field["seconds"])  # type: ignore[arg-type]
    print(f"Measured {date.today()} on {platform.machine()}, Python "
          f"{platform.python_version()}, {options.jobs} jobs, {seconds / 60:.0f} min in all; "
          "limits per case: 20 s, 1 GiB of address space above the fuzzer's."
          + ("" if real else f" (No real logs: {REAL_LOGS} is absent.)") + "\n")
    print("| seed log | cases | read | rejected | defects (crash / hang / memory / output) "
          "| slowest case s | peak RSS MB |")
    print("|---|---|---|---|---|---|---|")
    for name, s in seeds.items():
        print(f"| {name} | {s['cases']} | {s['read']} | {s['rejected']} | {s['defects']} "
              f"({s['crash']} / {s['hang']} / {s['memory']} / {s['output']}) | "
              f"{s['slowest_s']:.2f} | {s['peak_rss_mb']:.0f} |")
    if options.json is not None:
        options.json.write_text(json.dumps(seeds, indent=2) + "\n")
    return 1 if any(s["defects"] for s in seeds.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
