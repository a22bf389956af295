"""What a long silence costs: the fuzz campaign's seed dive (40 s) in every binary format
and as a MOOS alog (a text log whose times are its own),
as written and with its last 5 s moved 9.8 hours later (a recorder paused overnight, or a
damaged chunk whose clock jumped: the fuzz campaign's slowest case was such a log). Each is
put through what the fuzz harness does with a case (`inspect`, then `diagnose` to JSON, its
series and its summary), in a fresh process that has already imported the tool and loaded
the model, as a fuzz case's forked child has: wall time and peak RSS of that process.

Usage: python benchmarks/silence.py [--workdir DIR] [--formats bag,db3,...] [--json PATH]
"""

import argparse
import copy
import json
import platform
import subprocess
import sys
import tempfile
from datetime import date
from pathlib import Path

FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "tlog", "bin", "ulog", "alog"]
JUMP_S = 9.8 * 3600
MOVED_AFTER_S = 35.0

CHILD = """
import json, sys, time
from pathlib import Path
from auvdiag_cli import api
from auvdiag_cli.fuzz.harness import exercise
from auvdiag_cli.peak_memory import peak_rss_mb
profile = api.load_profile(None)
model = api.load_model(profile=profile)
started = time.perf_counter()
outcome, detail = exercise(Path(sys.argv[1]), profile, model)
seconds = time.perf_counter() - started
print(json.dumps({"outcome": outcome, "seconds": seconds, "peak_rss_mb": peak_rss_mb()}))
"""


def make_logs(workdir: Path, formats: list[str]) -> dict[tuple[str, str], Path]:
    """(format, "as written" | "9.8 h silence") -> the log."""
    from auvdiag_cli import api
    from auvdiag_cli.fuzz.seeds import SEED_SCENARIO, SEED_SECONDS, _cropped
    from auvdiag_cli.simulator.run import Stream, simulate
    from auvdiag_cli.simulator.scenarios import get_scenario
    from auvdiag_cli.simulator.writers import write_log

    profile = api.load_profile(None)
    dive = _cropped(simulate(get_scenario(SEED_SCENARIO, profile), profile, 7), SEED_SECONDS)

    def moved(stream: Stream) -> Stream:
        return Stream([t + JUMP_S if t > MOVED_AFTER_S else t for t in stream.times_s],
                      list(stream.values))

    paused = copy.copy(dive)
    paused.commands = moved(dive.commands)
    paused.sensors = {name: moved(stream) for name, stream in dive.sensors.items()}
    logs = {}
    for fmt in formats:
        for label, which in (("as written", dive), ("9.8 h silence", paused)):
            folder = workdir / label.replace(" ", "-").replace(".", "")
            folder.mkdir(parents=True, exist_ok=True)
            path = folder / (f"seed.{fmt}" if fmt in ("bag", "mcap", "tlog", "bin", "ulog")
                             else f"seed-{fmt}")
            write_log(which, profile, path, fmt)
            logs[fmt, label] = path
    return logs


def measure(path: Path) -> dict[str, float | str]:
    done = subprocess.run([sys.executable, "-c", CHILD, str(path)], capture_output=True,
                          text=True, check=True)
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workdir", type=Path, default=None)
    parser.add_argument("--formats", default=",".join(FORMATS))
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="auvdiag-silence-"))
    logs = make_logs(workdir, args.formats.split(","))
    results = {f"{fmt}, {label}": measure(path) for (fmt, label), path in logs.items()}
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    print(f"Measured {date.today()} on {platform.machine()}, Python "
          f"{platform.python_version()}; each log in a fresh process, after imports and "
          "the model load.\n")
    print("| log | as written: s | MB | 9.8 h silence: s | MB | outcome |")
    print("|---|---|---|---|---|---|")
    for fmt in args.formats.split(","):
        plain, paused = results[f"{fmt}, as written"], results[f"{fmt}, 9.8 h silence"]
        print(f"| {fmt} | {plain['seconds']:.2f} | {plain['peak_rss_mb']:.0f} | "
              f"{paused['seconds']:.2f} | {paused['peak_rss_mb']:.0f} | "
              f"{plain['outcome']}, {paused['outcome']} |")


if __name__ == "__main__":
    main()
