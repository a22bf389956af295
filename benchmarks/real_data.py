"""auvdiag on real vehicles' logs: skill per signal, horizon chosen, false alarms.

Data (read from ../shared/data, or --data; skipped with a message when absent):
- Haizhe AUV fault data set (Ji D., Mendeley Data, doi 10.17632/7rp2pmr6mx.1; Data in Brief
  39:107477, 2021; CC BY 4.0), train/ split. The Normal runs, in numeric order, are dealt
  out 3:1:1 to training, calibration (also the held-out set for the skill figures) and
  judgement; the model is trained with `auvdiag train`'s defaults, calibrated, and every
  judged Normal run and every run of each fault class is diagnosed.
- Real ArduSub logs (clydemcqueen/ardusub_log_tools, MIT): a model is trained on the
  operating (armed) time of small.BIN alone (its last 20 % held out), kept even without
  skill, and all three logs are diagnosed with it.

Usage: python benchmarks/real_data.py [--data DIR] [--iterations-scale 1.0]
"""

import argparse
import os
import platform
import re
import tempfile
import time
from collections import Counter
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from auvdiag_cli.training_job import TrainingResult

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
FAULT_CLASSES = ["AddWeight", "PressureGain_constant", "PropellerDamage_slight",
                 "PropellerDamage_bad"]


def _number(path: Path) -> int:
    found = re.findall(r"\d+", path.stem)
    return int(found[-1]) if found else 0


def _skill_table(result: "TrainingResult") -> list[str]:
    rows = ["| signal | skill | vs linear | model rms | hold rms | mean rms | judged |",
            "|---|---|---|---|---|---|---|"]
    for name, s in result.chosen.signals.items():
        rows.append(f"| {name} | {s.skill:.2f} | {s.versus_linear:.2f} | {s.model_rms:.4f} | "
                    f"{s.baseline_rms['hold']:.4f} | {s.baseline_rms['mean']:.4f} | "
                    f"{'yes' if s.judged else 'no'} |")
    return rows


def _horizon(result: "TrainingResult") -> str:
    h = result.chosen.horizon_s
    return "free run" if h is None else f"{h:g} s"


def haizhe(folder: Path, work: Path, scale: float) -> list[str]:
    from auvdiag_cli.calibration import calibrate
    from auvdiag_cli.diagnosis import diagnose
    from auvdiag_cli.profile import load_profile
    from auvdiag_cli.training_job import train_from_logs
    from models.store import load_model

    profile = load_profile(Path("haizhe"))
    normal = sorted((folder / "Normal").glob("*.csv"), key=_number)
    training = [p for i, p in enumerate(normal) if i % 5 < 3]
    calibration = [p for i, p in enumerate(normal) if i % 5 == 3]
    judged = [p for i, p in enumerate(normal) if i % 5 == 4]
    started = time.perf_counter()
    result = train_from_logs(training, work / "haizhe", profile, calibration,
                             iterations_scale=scale, keep_unskilled=True)
    trained_s = time.perf_counter() - started
    model = load_model(work / "haizhe")
    calibrate(model, profile, calibration)
    lines = [f"**Haizhe AUV** ({len(training)} Normal runs to train, {len(calibration)} to "
             f"calibrate and score, {len(judged)} judged; {result.operating_hours * 60:.1f} min "
             f"of operating time, trained in {trained_s:.0f} s). Horizon chosen: "
             f"{_horizon(result)}.", "", *_skill_table(result), ""]
    lines += ["| runs | diagnosed | alarms | rate | component named (count) |",
              "|---|---|---|---|---|"]
    for label, runs in [("Normal (held out)", judged),
                        *[(c, sorted((folder / c).glob("*.csv"), key=_number))
                          for c in FAULT_CLASSES]]:
        verdicts: Counter[str] = Counter()
        named: Counter[str] = Counter()
        for run in runs:
            d = diagnose(run, profile, model)
            verdicts[d.verdict] += 1
            if d.verdict == "fault":
                named[d.component or "/".join(d.candidates) or "unidentified"] += 1
        alarms = verdicts["fault"]
        lines.append(f"| {label} | {len(runs)} | {alarms} | {alarms / max(1, len(runs)):.0%} | "
                     + (", ".join(f"{k} ({v})" for k, v in named.most_common(3)) or "-")
                     + " |")
    return lines


def ardusub(folder: Path, work: Path, scale: float) -> list[str]:
    from auvdiag_cli.diagnosis import diagnose
    from auvdiag_cli.errors import AuvdiagError
    from auvdiag_cli.profile import load_profile
    from auvdiag_cli.training_job import train_from_logs
    from models.store import load_model

    profile = load_profile(Path("bluerov2_standard"))
    result = train_from_logs([folder / "small.BIN"], work / "rov", profile,
                             iterations_scale=scale, keep_unskilled=True)
    model = load_model(work / "rov")
    lines = [f"**ArduSub** (profile bluerov2_standard; trained on the armed time of small.BIN "
             f"alone, {result.operating_hours * 3600:.0f} s, held out: {result.heldout_split}). "
             f"Horizon chosen: {_horizon(result)}.", "", *_skill_table(result), "",
             "| log | verdict | alarm from | alarm inside operating time | not judged |",
             "|---|---|---|---|---|"]
    for name in ("small.BIN", "small.tlog", "pymavlink_bug.tlog"):
        try:
            d = diagnose(folder / name, profile, model)
        except AuvdiagError as error:
            lines.append(f"| {name} | not analysable: {str(error).split(': ')[-1]} | - | - | - |")
            continue
        raised = [k for k, v in d.b.items() if v]
        inside = "-"
        if d.detected_at_s is not None:
            index = int(abs(d.time_s - d.detected_at_s).argmin())
            # Outside operating time the sensors are set aside (NaN on the grid).
            measured = d.matching.measured[index] if d.matching is not None else []
            inside = "yes" if bool(np.isfinite(measured).any()) else "no"
        lines.append(f"| {name} | {d.verdict} | {', '.join(raised) or '-'} | {inside} | "
                     f"{', '.join(d.not_judged) or '-'} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--iterations-scale", type=float, default=1.0)
    args = parser.parse_args()
    if not args.data.is_dir():
        print(f"Real data not found at {args.data}: skipped (see the README for the data sets).")
        return
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), "
          f"Python {platform.python_version()}; data from {args.data}.\n")
    with tempfile.TemporaryDirectory() as work:
        for name, runner, sub in (("Haizhe", haizhe, "haizhe/train"),
                                  ("ArduSub", ardusub, "ardusub")):
            folder = args.data / sub
            if not folder.is_dir():
                print(f"{name}: not found at {folder}: skipped.\n")
                continue
            print("\n".join(runner(folder, Path(work), args.iterations_scale)) + "\n")


if __name__ == "__main__":
    main()
