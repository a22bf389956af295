"""The whole tool on a real nano-quadrotor as a user with a handful of normal flights runs
it: `auvdiag train` on four normal flights (no calibration: the thresholds as trained), then
`auvdiag diagnose` on every other normal flight and on every flight with a propeller cut by
2 mm or more, the verdict as the terminal gives it. `benchmarks/effort.py` measures the
effort shares alone; here every judge speaks (the replay, the effort shares, the commands
against the motion), as they do for a user.

Data: CrazyPAD (Masalimov K. et al., "CrazyPAD: A Dataset for Assessing the Impact of
Structural Defects on Nano-Quadcopter Performance", Data 2024, 9, 79, doi
10.3390/data9060079; MIT), series E8, read from ../shared/data/crazypad (or --data) with
the shipped `crazyflie` profile. Folds: four consecutive normal flights, cyclically (the
first --folds of the seven).

Usage: python benchmarks/whole_tool_crazypad.py [--data DIR] [--folds 7] > whole.md
"""

import argparse
import csv
import os
import platform
import tempfile
import time
from collections import Counter
from datetime import date
from pathlib import Path

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "crazypad"
TRAINED_ON = 4
MIN_CUT_MM = 2.0


def _flights(root: Path) -> tuple[list[Path], list[Path]]:
    """The normal flights and those with a propeller cut by MIN_CUT_MM or more."""
    with (root / "labels.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    normal = [root / r["file"] for r in rows if r["kind"] == "normal"]
    cut = [root / r["file"] for r in rows
           if r["kind"] == "cut" and float(r["cut_mm"] or 0) >= MIN_CUT_MM]
    return normal, cut


def _said(verdict: str, component: str | None, candidates: tuple[str, ...]) -> str:
    """The verdict and what it names: the component, or its candidates (an undetermined
    verdict's: what the logs cannot rule out)."""
    named = component or " or ".join(candidates)
    return f"{verdict}: {named}" if named else verdict


def fold_row(normal: list[Path], cut: list[Path], first: int, work: Path,
             totals: Counter[str]) -> str:
    from auvdiag_cli import api

    profile = api.load_profile("crazyflie")
    chosen = [normal[(first + k) % len(normal)] for k in range(TRAINED_ON)]
    model_dir = work / f"fold-{first}"
    api.train(chosen, profile, model_dir)
    model = api.load_model(model_dir, profile)
    judged_normal = Counter(_said(d.verdict.value, d.component, d.candidates) for d in (
        api.diagnose(p, profile, model) for p in normal if p not in chosen))
    judged_cut = Counter(_said(d.verdict.value, d.component, d.candidates) for d in (
        api.diagnose(p, profile, model) for p in cut))
    totals.update({"normal": sum(judged_normal.values()),
                   "normal alarmed": sum(n for v, n in judged_normal.items()
                                         if v.startswith("fault")),
                   "cut": sum(judged_cut.values()),
                   "cut found": sum(n for v, n in judged_cut.items() if v.startswith("fault")),
                   "cut named": judged_cut["fault: motor_3"],
                   "cut not ruled out": judged_cut["undetermined: motor_3"]})
    names = ", ".join(p.stem[-2:] for p in chosen)

    def counts(judged: Counter[str]) -> str:
        return ", ".join(f"{v} {n}" for v, n in judged.most_common())

    return (f"| {names} | {counts(judged_normal)} | {counts(judged_cut)} | "
            f"{judged_cut['fault: motor_3']} of {sum(judged_cut.values())} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--folds", type=int, default=7)
    args = parser.parse_args()
    if not (args.data / "labels.csv").is_file():
        print(f"CrazyPAD not found in {args.data}: nothing measured.")
        return
    normal, cut = _flights(args.data)
    started = time.perf_counter()
    totals: Counter[str] = Counter()
    with tempfile.TemporaryDirectory() as work:
        rows = [fold_row(normal, cut, first, Path(work), totals)
                for first in range(min(args.folds, len(normal)))]
    print("\n".join([
        f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), in "
        f"{(time.perf_counter() - started) / 60:.1f} min: CrazyPAD E8 (Masalimov K. et al., "
        "Data 2024, 9, 79, doi 10.3390/data9060079; MIT), profile `crazyflie`; each fold "
        f"trains on {TRAINED_ON} normal flights (`train`, one of them held out by it; no "
        f"calibration) and diagnoses the other {len(normal) - TRAINED_ON} normal flights and "
        f"the {len(cut)} flights with the motor 3 propeller cut by {MIN_CUT_MM:g} mm or more.",
        "",
        "| trained on (normal flights) | other normal flights: verdicts | cut flights: "
        "verdicts | motor 3 named |",
        "|---|---|---|---|", *rows, "",
        f"In all: normal flights alarmed {totals['normal alarmed']} of {totals['normal']}; "
        f"cut flights found {totals['cut found']} of {totals['cut']}, motor 3 named in "
        f"{totals['cut named']}; undetermined with motor 3 the candidate (the few normal "
        f"flights cannot rule it out) in {totals['cut not ruled out']}."]))


if __name__ == "__main__":
    main()
