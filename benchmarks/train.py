"""Training time, held-out error and skill on one hour of 10 Hz logs: the trainer as it runs
now against the trainer as it ran before (torch's default thread count), same logs, same
stages, same seed, in one run.

Logs: simulated Twin-Burger normal dives (missions of every size, speed and direction, DMSs,
open-loop excitation) until --minutes of 10 Hz data, written as real MCAP logs; held out:
one dive of each mission scenario with other seeds. With --busy, one other process keeps a
core busy during both trainings (a laptop running a browser, a CI runner with a neighbour).

Usage: python benchmarks/train.py [--minutes 60] [--busy]
"""

import argparse
import multiprocessing
import os
import platform
import tempfile
import time
from collections.abc import Callable, Sequence
from datetime import date
from pathlib import Path

import numpy as np

SCENARIOS = ["paper-normal", "mission-ccw", "mission-large-cw", "mission-large-ccw",
             "mission-fast-cw", "mission-fast-ccw", "mission-sprint-cw", "mission-sprint-ccw",
             "all-dms-and-mission", "excitation"]


def _spin() -> None:
    while True:
        pass


def simulated_logs(work: Path, minutes: float) -> tuple[list[Path], list[Path]]:
    from auvdiag_cli import api

    profile = api.load_profile()
    training: list[Path] = []
    total_s, seed = 0.0, 1
    while total_s < minutes * 60:
        for name in SCENARIOS:
            path = work / f"{name}-s{seed}"
            dive = api.simulate(name, profile, path, log_format="ros2-mcap", seed=seed)
            training.append(path)
            total_s += dive.duration_s
            if total_s >= minutes * 60:
                break
        seed += 1
    heldout = []
    for name in SCENARIOS:
        path = work / f"heldout-{name}"
        api.simulate(name, profile, path, log_format="ros2-mcap", seed=901)
        heldout.append(path)
    return training, heldout


def run(label: str, train_function: Callable[..., object], logs: list[Path],
        heldout: list[Path], output: Path, scale: float) -> dict:
    from auvdiag_cli.api import TrainOptions, load_profile
    from auvdiag_cli.jobs.train import train_from_logs

    started = time.perf_counter()
    result = train_from_logs(logs, output, load_profile(), TrainOptions(
        tuple(heldout), iterations_scale=scale, keep_unskilled=True), trainer=train_function)
    seconds = time.perf_counter() - started
    return {"label": label, "seconds": seconds, "hours": result.operating_hours,
            "signals": {k: (s.model_rms, s.skill, s.versus_linear)
                        for k, s in result.chosen.signals.items()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--busy", action="store_true")
    parser.add_argument("--iterations-scale", type=float, default=1.0,
                        help="shorten every stage (e.g. 0.1 for --busy: the old trainer "
                             "crawls there)")
    args = parser.parse_args()
    import torch

    from models import training

    def before(sequences: Sequence[training.TrainingLog], hidden: int,
               stages: Sequence[training.Stage], seed: int,
               progress: Callable[[str], None] | None, linear: np.ndarray | None = None,
               run: tuple[int, int] = (1, 1)) -> object:
        """The trainer as it was: torch's default thread count."""
        tracker = training._Progress(stages, training._horizons(sequences, stages), progress,
                                     run)
        return training._train(sequences, hidden, stages, 64, seed, tracker, linear)

    with tempfile.TemporaryDirectory() as work:
        logs, heldout = simulated_logs(Path(work), args.minutes)
        spinner = None
        if args.busy:
            spinner = multiprocessing.Process(target=_spin, daemon=True)
            spinner.start()
        try:
            results = [run("now", training.train, logs, heldout, Path(work) / "now",
                           args.iterations_scale),
                       run(f"before (torch default, {torch.get_num_threads()} threads)",
                           before, logs, heldout, Path(work) / "before", args.iterations_scale)]
        finally:
            if spinner is not None:
                spinner.terminate()
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), "
          f"Python {platform.python_version()}, torch {torch.__version__}; "
          f"{results[0]['hours']:.2f} h of 10 Hz Twin-Burger logs ({len(logs)} simulated "
          f"dives), held out: {len(heldout)} dives of other seeds; default stages"
          + (f" x {args.iterations_scale:g} iterations" if args.iterations_scale != 1 else "")
          + ", seed 0"
          + ("; one other process kept a core busy" if args.busy else "") + ".\n")
    names = list(results[0]["signals"])
    print("| trainer | time | " + " | ".join(f"{n}: held-out rms / skill / vs linear"
                                            for n in names) + " |")
    print("|---|---|" + "---|" * len(names))
    for r in results:
        cells = " | ".join(f"{rms:.4f} / {skill:.2f} / {linear:.2f}"
                           for rms, skill, linear in r["signals"].values())
        print(f"| {r['label']} | {r['seconds']:.0f} s | {cells} |")
    ratio = results[1]["seconds"] / results[0]["seconds"]
    print(f"\nNow / before: {ratio:.2f}x faster; now {results[0]['seconds'] / 60:.1f} min for "
          f"{results[0]['hours']:.2f} h of logs.")


if __name__ == "__main__":
    main()
