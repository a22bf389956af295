"""Where the time of a diagnosis goes, against what the hardware and the raw readers allow.

Simulates a one-hour Twin-Burger dive (16 x ZA, ZB, ZC and the paper's mission; commands and
flow at 10 Hz, IMU at 50 Hz) and writes it in every format. Then, each in a fresh process:
  startup     importing the CLI, and torch on its own;
  diagnose    `auvdiag diagnose` of the one-hour log, end to end, per format: wall time and
              peak RSS, split into reading the log, replaying the model (matching) and the
              rest (segments, detection, reports); and the command as a user runs it, in a
              process of its own (interpreter and CLI start-up included);
  raw read    the raw library decoding the same topics (benchmarks/ingest.py's reader);
              each reader finds the log's files in the page cache (read once before);
              diagnose, command and raw read are each the median of --runs runs (default
              3), alternated, so that a slow moment of the machine lands on all of them;
  replay      the model over 36 000 steps: torch module, NumPy path, and the NumPy path
              batched over 16 logs; the model's FLOPs per step against one core's float32
              matrix-multiply rate.

Usage: python benchmarks/speed.py [--workdir DIR] [--formats bag,db3,...] [--json PATH]
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

from bytecode import write_bytecode  # benchmarks/bytecode.py, beside this script

ONE_THREAD = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}
FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "tlog", "bin", "ulog", "alog"]
REPLAY_STEPS, BATCH = 36_000, 16
FAULTY = "mcap, faulty"


def make_logs(workdir: Path, formats: list[str]) -> dict[str, Path]:
    """The one-hour dive in every format, and (key ``mcap, faulty``) the same hour with
    thruster 0 dead from minute 30, whose diagnosis also runs the isolation steps."""
    from auvdiag_cli.simulator.faults import Fault
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import DMS_ALL, PAPER_MISSION, Scenario
    from auvdiag_cli.simulator.writers import write_log
    from auvdiag_cli.vehicle.profile import load_profile

    profile = load_profile()
    steps = (DMS_ALL + PAPER_MISSION) * 16
    dives = {"normal": Scenario("one-hour", "16 x (ZA, ZB, ZC, mission)", steps),
             "faulty": Scenario("one-hour-fault", "thruster 0 dead from 30 min", steps,
                                Fault("thruster_0", "dead", 1800.0),
                                run_after_fault_s=1800.0)}
    wanted = {fmt: (fmt, "normal") for fmt in formats} | {FAULTY: ("mcap", "faulty")}
    paths = {}
    for key, (fmt, kind) in wanted.items():
        name = {"bag": "dive.bag", "mcap": "dive.mcap", "tlog": "dive.tlog",
                "bin": "dive.bin", "ulog": "dive.ulog"}.get(fmt, f"dive_{fmt}")
        path = workdir / (name if kind == "normal" else f"faulty-{name}")
        if not path.exists():
            write_log(simulate(dives[kind], profile, seed=1), profile, path, fmt)
        paths[key] = path
    return paths


def child_startup(what: str) -> dict:
    started = time.perf_counter()
    if what == "cli":
        import auvdiag_cli.cli  # noqa: F401
    else:
        import torch  # noqa: F401
    return {"seconds": time.perf_counter() - started}


def child_diagnose(path: Path) -> dict:
    """The diagnose command's work, timed by stage (same calls as `auvdiag diagnose`)."""
    started = time.perf_counter()
    from auvdiag_cli.engine import ingest as ingest_module
    from auvdiag_cli.engine import residuals as matching_module
    from auvdiag_cli.engine.diagnosis import diagnose
    from auvdiag_cli.reports.json_report import diagnosis_to_dict
    from auvdiag_cli.vehicle.profile import load_profile
    from models.store import load_model

    stages = {"read": 0.0, "replay": 0.0}

    def timed(function: object, stage: str) -> object:
        def wrapper(*args: object, **kwargs: object) -> object:
            begun = time.perf_counter()
            try:
                return function(*args, **kwargs)  # type: ignore[operator]
            finally:
                stages[stage] += time.perf_counter() - begun
        return wrapper

    import auvdiag_cli.engine.diagnosis as diagnosis_module

    diagnosis_module.ingest = timed(ingest_module.ingest, "read")  # type: ignore[assignment]
    diagnosis_module.match = timed(matching_module.match, "replay")  # type: ignore[assignment]
    profile = load_profile()
    imported = time.perf_counter() - started
    model = load_model()
    result = diagnose(path, profile, model)
    diagnosis_to_dict(result)
    total = time.perf_counter() - started
    from auvdiag_cli.peak_memory import peak_rss_mb

    return {"total_s": total, "imports_s": imported, **{f"{k}_s": v for k, v in stages.items()},
            "rest_s": total - imported - sum(stages.values()), "peak_mb": peak_rss_mb(),
            "steps": int(result.histories.time_s.size), "verdict": result.verdict}


def child_raw(path: Path, fmt: str) -> dict:
    sys.path.insert(0, str(Path(__file__).parent))
    from ingest import read_raw  # the raw-library reader of the ingest benchmark

    started = time.perf_counter()
    count = read_raw(path, fmt)
    return {"messages": count, "seconds": time.perf_counter() - started}


def child_replay() -> dict:
    import numpy as np

    from models.dynamics import replay
    from models.fast import Engine, fast_replay, fast_replay_batch
    from models.store import load_model

    model = load_model()
    rng = np.random.default_rng(0)
    commands = np.repeat(rng.uniform(-0.8, 0.8, (REPLAY_STEPS // 50, 2)), 50, axis=0)
    start = np.array([0.05, 0.0])

    def seconds(run: object) -> float:
        begun = time.perf_counter()
        run()  # type: ignore[operator]
        return time.perf_counter() - begun

    def rate(run: object, samples: int) -> float:
        return samples / min(seconds(run) for _ in range(3))

    def one(engine: Engine) -> object:
        return lambda: fast_replay(model.fast, model.normaliser, commands, start, engine)

    def batched(engine: Engine) -> object:
        return lambda: fast_replay_batch(model.fast, model.normaliser, [commands] * BATCH,
                                         [start] * BATCH, engine)

    # The first compiled call in a process loads numba and the cached kernel.
    compiled_load_s = seconds(lambda: fast_replay(model.fast, model.normaliser, commands[:2],
                                                  start, "compiled"))
    rates = {
        "torch_steps_per_s": rate(lambda: replay(model.network, model.normaliser, commands,
                                                 start), REPLAY_STEPS),
        "numpy_steps_per_s": rate(one("numpy"), REPLAY_STEPS),
        "numpy_batched_samples_per_s": rate(batched("numpy"), REPLAY_STEPS * BATCH),
        "compiled_steps_per_s": rate(one("compiled"), REPLAY_STEPS),
        "compiled_batched_samples_per_s": rate(batched("compiled"), REPLAY_STEPS * BATCH),
    }
    hidden, n_c, n_s = model.fast.hidden, len(model.command_names), len(model.sensor_names)
    # multiply-adds of the GRU (input and hidden gates), the head's two layers; x2 for FLOPs
    flops_per_step = 2 * (3 * hidden * (n_c + n_s) + 3 * hidden * hidden
                          + hidden * (hidden + n_c + n_s) + hidden * n_s)
    a = rng.standard_normal((1024, 1024), dtype=np.float32)
    begun = time.perf_counter()
    for _ in range(5):
        a @ a
    matmul_flops = 5 * 2 * 1024**3 / (time.perf_counter() - begun)
    return {**rates, "compiled_load_s": compiled_load_s, "flops_per_step": flops_per_step,
            "core_matmul_gflops": matmul_flops / 1e9,
            "compiled_gflops": rates["compiled_steps_per_s"] * flops_per_step / 1e9}


def command_seconds(path: Path) -> float:
    """``auvdiag diagnose PATH --quiet`` as a user runs it: the wall time."""
    begun = time.perf_counter()
    subprocess.run([sys.executable, "-m", "auvdiag_cli", "diagnose", str(path), "--quiet"],
                   env=ONE_THREAD, check=False, capture_output=True)
    return time.perf_counter() - begun


def median_of(runs: list[dict], key: str) -> dict:
    """The run whose ``key`` is the median (its other figures stay those of one run)."""
    return sorted(runs, key=lambda run: run[key])[len(runs) // 2]


def measure_format(path: Path, fmt: str, runs: int) -> dict:
    diagnosed, raw, commands = [], [], []
    for _ in range(runs):
        warm_cache(path)
        diagnosed.append(in_child("diagnose", str(path)))
        warm_cache(path)
        raw.append(in_child("raw", str(path), fmt.split(",")[0]))
        commands.append({"seconds": command_seconds(path)})
    raw_read = median_of(raw, "seconds")
    return {**median_of(diagnosed, "total_s"), "raw_read_s": raw_read["seconds"],
            "raw_messages": raw_read["messages"],
            "command_s": median_of(commands, "seconds")["seconds"], "runs": runs}


def warm_cache(path: Path) -> None:
    """Read the log's files once, so that every reader measured finds them in the page
    cache (as right after copying a log off the vehicle). Without this the first reader
    of a log pays the disk and the second does not."""
    for file in ([path] if path.is_file() else sorted(path.iterdir())):
        with file.open("rb") as stream:
            while stream.read(8 << 20):
                pass


def in_child(*args: str) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", *args], capture_output=True,
                         text=True, check=True, env=ONE_THREAD)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workdir", type=Path)
    parser.add_argument("--formats", default=",".join(FORMATS))
    parser.add_argument("--json", type=Path)
    parser.add_argument("--runs", type=int, default=3, help="runs per figure (the median)")
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        kind, *rest = args.child
        result = {"startup": lambda: child_startup(rest[0]),
                  "diagnose": lambda: child_diagnose(Path(rest[0])),
                  "raw": lambda: child_raw(Path(rest[0]), rest[1]),
                  "replay": child_replay}[kind]()
        print(json.dumps(result))
        return
    write_bytecode()          # as on an installed copy: no process compiles the sources
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="auvdiag-speed-"))
    workdir.mkdir(parents=True, exist_ok=True)
    formats = args.formats.split(",")
    paths = make_logs(workdir, formats)
    report: dict = {"date": str(date.today()), "machine": platform.machine(),
                    "cores": os.cpu_count(), "python": platform.python_version()}
    report["startup"] = {what: in_child("startup", what)["seconds"] for what in ("cli", "torch")}
    in_child("replay")    # compiles the kernel into numba's cache where a fresh copy has none
    report["replay"] = in_child("replay")
    report["formats"] = {}
    for fmt, path in paths.items():
        report["formats"][fmt] = measure_format(path, fmt, args.runs)
        print(fmt, json.dumps(report["formats"][fmt]), file=sys.stderr, flush=True)
    print(render(report))
    if args.json:
        args.json.write_text(json.dumps(report, indent=2))


def render(report: dict) -> str:
    r = report["replay"]
    lines = [
        f"Measured {report['date']} on {report['machine']}, {report['cores']} cores, Python "
        f"{report['python']}, one thread per process; each figure of a format is the median "
        f"of {next(iter(report['formats'].values()))['runs']} runs.",
        "",
        f"Startup: importing the CLI {report['startup']['cli']:.2f} s (torch is imported only "
        f"when a model is loaded: {report['startup']['torch']:.2f} s on its own).",
        "",
        "| replay of the model | samples/s |",
        "|---|---|",
        f"| torch module, one log | {r['torch_steps_per_s']:,.0f} |",
        f"| NumPy path, one log | {r['numpy_steps_per_s']:,.0f} |",
        f"| NumPy path, {BATCH} logs batched | {r['numpy_batched_samples_per_s']:,.0f} |",
        f"| compiled loop, one log | {r['compiled_steps_per_s']:,.0f} |",
        f"| compiled loop, {BATCH} logs batched | {r['compiled_batched_samples_per_s']:,.0f} |",
        "",
        f"A one-hour 10 Hz log ({REPLAY_STEPS:,} steps) replays in "
        f"{REPLAY_STEPS / r['compiled_steps_per_s']:.3f} s on the compiled loop, after "
        f"{r['compiled_load_s']:.2f} s to load numba and the cached kernel once per process. "
        f"The model costs {r['flops_per_step']:,} FLOPs a step; one core multiplies float32 "
        f"matrices at {r['core_matmul_gflops']:.1f} GFLOP/s, so the arithmetic alone would "
        f"allow {r['core_matmul_gflops'] * 1e9 / r['flops_per_step']:,.0f} steps/s; the "
        f"compiled loop reaches {r['compiled_gflops']:.2f} GFLOP/s (a step is a chain of "
        "small dependent dot products, which neither vectorise wide nor overlap; the NumPy "
        "loop pays about a dozen array calls of Python overhead a step).",
        "",
        "| format | diagnose, end to end | imports | read log | replay + g | rest | peak RSS "
        "| raw library read | diagnose ÷ raw read | `auvdiag diagnose` command |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for fmt, f in report["formats"].items():
        lines.append(f"| {fmt} ({f['verdict']}) | {f['total_s']:.2f} s | {f['imports_s']:.2f} s | "
                     f"{f['read_s']:.2f} s | {f['replay_s']:.2f} s | {f['rest_s']:.2f} s | "
                     f"{f['peak_mb']:.0f} MB | {f['raw_read_s']:.2f} s | "
                     f"{f['total_s'] / f['raw_read_s']:.2f} | {f['command_s']:.2f} s |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
