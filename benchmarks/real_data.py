"""auvdiag on real vehicles' logs: skill per signal, horizon chosen, false alarms.

Data (read from ../shared/data, or --data; skipped with a message when absent):
- Haizhe AUV fault data set (Ji D., Mendeley Data, doi 10.17632/7rp2pmr6mx.1; Data in Brief
  39:107477, 2021; CC BY 4.0), train/ split, cross-validated (--folds, default 5): in each
  fold the Normal runs, in numeric order, are dealt out to training, calibration (also the
  held-out set for the skill figures) and judgement; the model is trained with `auvdiag
  train`'s defaults, calibrated, and the judged Normal runs and every run of each fault
  class are diagnosed.
- CrazyPAD (Masalimov K. et al., Data 2024, 9, 79, doi 10.3390/data9060079; MIT), series
  E8: skill per motion signal from the normal flights (four train, the rest held out).
- Real ArduSub logs (clydemcqueen/ardusub_log_tools, MIT): a model is trained on the
  operating (armed) time of small.BIN alone (its last 20 % held out), kept even without
  skill, and all three logs are diagnosed with it.

Usage: python benchmarks/real_data.py [--data DIR] [--iterations-scale 1.0] [--folds 5]
"""

import argparse
import os
import platform
import re
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from auvdiag_cli.engine.results import Diagnosis
    from auvdiag_cli.jobs.train import TrainingResult
    from auvdiag_cli.vehicle.profile import Profile

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
FALSE_ALARM_RATE = 0.05       # calibrate's budget: a share of normal runs
FAULT_CLASSES = ["AddWeight", "PressureGain_constant", "PropellerDamage_slight",
                 "PropellerDamage_bad"]


def _number(path: Path) -> int:
    found = re.findall(r"\d+", path.stem)
    return int(found[-1]) if found else 0


def _skill_table(result: "TrainingResult") -> list[str]:
    rows = ["| signal | read from | skill | vs linear | model rms | hold rms | mean rms | judged |",
            "|---|---|---|---|---|---|---|---|"]
    for name, s in result.chosen.signals.items():
        rows.append(f"| {name} | {result.chosen.predictors.get(name, 'network')} | "
                    f"{s.skill:.2f} | {s.versus_linear:.2f} | {s.model_rms:.4f} | "
                    f"{s.baseline_rms['hold']:.4f} | {s.baseline_rms['mean']:.4f} | "
                    f"{'yes' if s.judged else 'no'} |")
    return rows


def _horizon(result: "TrainingResult") -> str:
    h = result.chosen.horizon_s
    return "free run" if h is None else f"{h:g} s"


def _score(diagnosis: "Diagnosis") -> float:
    """The run's largest ratio to a threshold (the alarm's margin): g over the judged
    signals, a start's deviation over its allowance, an actuator's extra effort."""
    ratios = [0.0]
    matching = diagnosis.histories.matching
    if matching is not None:
        judged = [i for i, n in enumerate(diagnosis.histories.sensor_names)
                  if n not in diagnosis.not_judged]
        with np.errstate(invalid="ignore", divide="ignore"):
            g = matching.g_percent[:, judged] / diagnosis.histories.thresholds[:, judged]
        ratios += [float(np.nanmax(g))] if np.isfinite(g).any() else []
    start = diagnosis.start_check
    if start is not None and start.judged:
        ratios += [abs(start.deviation[n]) / t for n, t in start.thresholds.items()]
    check = diagnosis.command_check
    if check is not None:
        ratios += [r for r in check.peak_ratio.values() if r is not None]
    return max(ratios)


def _auc(positives: list[float], negatives: list[float]) -> float:
    """P(a faulty run scores above a normal one), ties counting half (Mann-Whitney)."""
    pos, neg = np.asarray(positives)[:, None], np.asarray(negatives)[None, :]
    return float(((pos > neg) + 0.5 * (pos == neg)).mean())


@dataclass
class HaizheFolds:
    """What the folds gave: per class, each run's score, alarms and the components named."""

    scores: dict[str, list[float]]
    alarms: Counter[str]
    named: dict[str, Counter[str]]
    results: list["TrainingResult"] = field(default_factory=list)
    # The same folds without the profile's measured inputs (the linear predictors only).
    without_inputs: list["TrainingResult"] = field(default_factory=list)
    horizons: list[str] = field(default_factory=list)
    loo: list[tuple[int, int]] = field(default_factory=list)     # alarmed, calibration runs
    seconds: float = 0.0


def _haizhe_folds(normal: list[Path], faulty: dict[str, list[Path]], work: Path, scale: float,
                  folds: int) -> HaizheFolds:
    from auvdiag_cli import api

    profile = api.load_profile("haizhe")
    labels = ["Normal (held out)", *faulty]
    out = HaizheFolds({c: [] for c in labels}, Counter(), {c: Counter() for c in labels})
    for fold in range(folds):
        judged = [p for i, p in enumerate(normal) if i % folds == fold]
        calibration = [p for i, p in enumerate(normal) if i % folds == (fold + 1) % folds]
        training = [p for p in normal if p not in judged and p not in calibration]
        started = time.perf_counter()
        result = api.train(training, profile, work / f"haizhe{fold}", options=api.TrainOptions(
            tuple(calibration), iterations_scale=scale, keep_unskilled=True))
        out.seconds += time.perf_counter() - started
        out.results.append(result)
        if profile.inputs:
            out.without_inputs.append(api.train(
                training, replace(profile, inputs=()), work / f"haizhe{fold}-without-inputs",
                options=api.TrainOptions(tuple(calibration), keep_unskilled=True,
                                 predictors=("linear", "linear-replay"))))
        out.horizons.append(_horizon(result))
        model = api.load_model(work / f"haizhe{fold}", profile)
        budget = api.calibrate(calibration, profile, model, options=api.CalibrateOptions(
            budget=api.FalseAlarmBudget(FALSE_ALARM_RATE))).budget
        assert budget is not None
        out.loo.append((budget.loo_logs_alarmed, budget.logs))
        for label, runs in [("Normal (held out)", judged), *faulty.items()]:
            for run in runs:
                d = api.diagnose(run, profile, model)
                out.scores[label].append(_score(d))
                if d.verdict == "fault":
                    out.alarms[label] += 1
                    out.named[label][d.component or "/".join(d.candidates)
                                     or "unidentified"] += 1
    return out


def _skills(results: list["TrainingResult"], signal: str) -> str:
    return ", ".join(f"{s.skill:.2f}" + ("" if s.judged else " (not judged)")
                     for s in (r.chosen.signals[signal] for r in results)) or "-"


def haizhe(folder: Path, work: Path, scale: float, folds: int) -> list[str]:
    """Cross-validated within train/: in fold f the Normal runs numbered i with i % folds == f
    are judged, those with i % folds == f + 1 calibrate (and score the skill), the rest
    train; every faulty run is diagnosed in every fold."""
    from auvdiag_cli.reports.training import relation_lines
    from auvdiag_cli.vehicle.profile import load_profile

    normal = sorted((folder / "Normal").glob("*.csv"), key=_number)
    faulty = {c: sorted((folder / c).glob("*.csv"), key=_number) for c in FAULT_CLASSES}
    run = _haizhe_folds(normal, faulty, work, scale, folds)
    first = run.results[0]
    profile = load_profile(Path("haizhe"))
    lines = [f"**Haizhe AUV**, {folds}-fold cross-validation within train/ ({len(normal)} Normal "
             f"runs; per fold about {len(normal) * (folds - 2) // folds} to train, "
             f"{len(normal) // folds} to calibrate and score, {len(normal) // folds} judged; "
             f"{first.operating_hours * 60:.1f} min of operating time in fold 1; training "
             f"{run.seconds / folds:.0f} s a fold). Horizon chosen per fold: "
             f"{', '.join(run.horizons)}. Depth skill per fold: "
             + _skills(run.results, "depth") + ". The model is driven by the command and the "
             "profile's measured inputs (" + ", ".join(profile.input_names) + "); without "
             "them (the linear predictors, which win on depth here), depth skill per fold: "
             + _skills(run.without_inputs, "depth") + "; yaw rate: "
             + _skills(run.without_inputs, "yaw_rate") + " (with them: "
             + _skills(run.results, "yaw_rate") + "). Skill in fold 1:", "",
             *_skill_table(first), "",
             f"Thresholds set by `calibrate --false-alarm-rate {FALSE_ALARM_RATE}` on each "
             "fold's calibration runs; leaving each calibration run out, "
             + ", ".join(f"{a} of {n}" for a, n in run.loo) + " alarmed (per fold).", "",
             "| runs | diagnosed (all folds) | alarms | rate | AUC of the score against "
             "held-out Normal | component named (count) |", "|---|---|---|---|---|---|"]
    normal_scores = run.scores["Normal (held out)"]
    for label, values in run.scores.items():
        auc = "-" if label.startswith("Normal") else f"{_auc(values, normal_scores):.2f}"
        lines.append(f"| {label} | {len(values)} | {run.alarms[label]} | "
                     f"{run.alarms[label] / max(1, len(values)):.0%} | {auc} | "
                     + (", ".join(f"{k} ({v})" for k, v in run.named[label].most_common(3))
                        or "-") + " |")
    lines += ["", "The score of a run is its largest ratio to a threshold: g over the judged "
              "signals, the start's deviation from the normal start, an actuator's extra "
              "effort; the AUC is the chance that a faulty run scores above a held-out Normal "
              "one.",
              "", "Commands against the motion, fold 1: "
              + "; ".join(" ".join(line.split()).rstrip(":") for line in relation_lines(
                  first.command_relations, profile.command_names)), ""]
    return lines + separability(folder, folds)


# Per-run statistics of the Haizhe columns, for the separability ceiling.
CEILING_COLUMNS = ["depth", "roll", "pitch", "a_x", "a_y", "a_z", "w_row", "w_pitch", "w_yaw",
                   "voltage"]


def _run_statistics(path: Path) -> dict[str, float]:
    import pandas as pd

    table = pd.read_csv(path)
    stats = {}
    for column in CEILING_COLUMNS:
        values = table[column].to_numpy(dtype=float)
        stats.update({f"mean {column}": values.mean(), f"std {column}": values.std(),
                      f"step std {column}": np.diff(values).std()})
    stats["depth over the first second"] = float(np.median(table["depth"].to_numpy()[:18]))
    return stats


def _calibrated_detection(normal: np.ndarray, faulty: np.ndarray, folds: int) -> list[float]:
    """Per fold (the folds of `haizhe`): the class's share beyond 1.5 x the largest deviation
    of the calibration runs from the training runs' median (calibrate's rule)."""
    index = np.arange(len(normal))
    shares = []
    for fold in range(folds):
        calibration = normal[index % folds == (fold + 1) % folds]
        training = normal[(index % folds != fold) & (index % folds != (fold + 1) % folds)]
        centre = np.median(training)
        shares.append(float((np.abs(faulty - centre) > 1.5 * np.abs(calibration - centre).max())
                            .mean()))
    return shares


def separability(folder: Path, folds: int) -> list[str]:
    """How far any one per-run statistic tells a class from Normal: each statistic scored
    as its distance from the Normal runs' mean in Normal standard deviations; the best per
    class is chosen with the fault labels, so this is an optimistic ceiling for any single
    statistic, not a method."""
    stats = {label: [_run_statistics(p) for p in sorted((folder / label).glob("*.csv"),
                                                         key=_number)]
             for label in ["Normal", *FAULT_CLASSES]}
    normal = stats["Normal"]
    lines = ["Separability ceiling: the best single per-run statistic per class (its distance "
             "from the Normal mean in Normal standard deviations; chosen with the labels, so "
             "optimistic), the share of the class beyond the 95th percentile of the Normal "
             "runs (detection at 5 % false alarms), and beyond a threshold set by calibrate's "
             "rule (no calibration run over it) in each fold:", "",
             "| class | best statistic | AUC | detection at 5 % false alarms | with calibrate's "
             "rule, per fold |", "|---|---|---|---|---|"]
    for label in FAULT_CLASSES:
        best = (0.0, "", 0.0)
        for key in normal[0]:
            reference = np.array([r[key] for r in normal])
            mean, spread = reference.mean(), reference.std() + 1e-12
            negatives = np.abs(reference - mean) / spread
            positives = np.abs(np.array([r[key] for r in stats[label]]) - mean) / spread
            auc = _auc(list(positives), list(negatives))
            if auc > best[0]:
                best = (auc, key, float((positives > np.quantile(negatives, 0.95)).mean()))
        per_fold = _calibrated_detection(np.array([r[best[1]] for r in normal]),
                                         np.array([r[best[1]] for r in stats[label]]), folds)
        lines.append(f"| {label} | {best[1]} | {best[0]:.2f} | {best[2]:.0%} | "
                     + ", ".join(f"{share:.0%}" for share in per_fold) + " |")
    return lines


def ardusub(folder: Path, work: Path, scale: float) -> list[str]:
    from auvdiag_cli import api
    from auvdiag_errors import AuvdiagError

    profile = api.load_profile("bluerov2_standard")
    result = api.train([folder / "small.BIN"], profile, work / "rov",
                       options=api.TrainOptions(iterations_scale=scale, keep_unskilled=True))
    model = api.load_model(work / "rov", profile)
    lines = [f"**ArduSub** (profile bluerov2_standard; trained on small.BIN alone: "
             f"{result.operating_hours * 3600:.0f} s of its armed time, the rest held out "
             f"({result.heldout_split})). "
             f"Horizon chosen: {_horizon(result)}.", "", *_skill_table(result), "",
             "| log | verdict | alarm from | alarm inside operating time | not judged |",
             "|---|---|---|---|---|"]
    for name in ("small.BIN", "small.tlog", "pymavlink_bug.tlog"):
        try:
            d = api.diagnose(folder / name, profile, model)
        except AuvdiagError as error:
            lines.append(f"| {name} | not analysable: {str(error).split(': ')[-1]} | - | - | - |")
            continue
        raised = [k for k, v in d.b.items() if v]
        inside = "-"
        if d.detected_at_s is not None:
            index = int(abs(d.histories.time_s - d.detected_at_s).argmin())
            # Outside operating time the sensors are set aside (NaN on the grid).
            matching = d.histories.matching
            measured = matching.measured[index] if matching is not None else []
            inside = "yes" if bool(np.isfinite(measured).any()) else "no"
        lines.append(f"| {name} | {d.verdict} | {', '.join(raised) or '-'} | {inside} | "
                     f"{', '.join(d.not_judged) or '-'} |")
    return lines


# The crazyflie profile's motion signals, and two more the flights log: the vertical
# acceleration (what the motor commands set directly) and the height.
CRAZYPAD_EXTRA_SENSORS = {"az": ("stateEstimate_az", "m/s^2", 2.0),
                          "z": ("stateEstimate_z", "m", 1.0)}


def _crazypad_profile(work: Path) -> Path:
    """The shipped crazyflie profile with the extra sensors (thresholds as vz's)."""
    from auvdiag_cli.vehicle.profile import profile_text

    text, _ = profile_text(Path("crazyflie"))
    blocks = "".join(f'[[sensors]]\nname = "{name}"\ncomponent = "state_estimate"\n'
                     f'unit = "{unit}"\nfull_scale = {scale}\n\n'
                     for name, (_, unit, scale) in CRAZYPAD_EXTRA_SENSORS.items())
    text = text.replace("[[effort]]", blocks + "[[effort]]", 1)
    text = text.replace("vz = 15.0\n", "vz = 15.0\n" + "".join(
        f"{name} = 15.0\n" for name in CRAZYPAD_EXTRA_SENSORS), 1)
    text = text.replace("b = { vx = 0, vy = 0, vz = 0 }", "b = { vx = 0, vy = 0, vz = 0, "
                        + ", ".join(f"{n} = 0" for n in CRAZYPAD_EXTRA_SENSORS) + " }")
    text += "".join(f'{name} = {{ column = "{column}" }}\n'
                    for name, (column, _, _) in CRAZYPAD_EXTRA_SENSORS.items())
    path = work / "crazyflie_motion.toml"
    path.write_text(text)
    return path


def crazypad(root: Path, work: Path, scale: float) -> list[str]:
    """Skill per motion signal from the normal flights: the first four train, the rest are
    held out; each signal read from the predictor that validates best."""
    import csv

    from auvdiag_cli import api

    with (root / "labels.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    normal = [root / row["file"] for row in rows if row["kind"] == "normal"]
    defects = [root / row["file"] for row in rows if row["kind"] != "normal"]
    profile = api.load_profile(_crazypad_profile(work))
    result = api.train(normal[:4], profile, work / "crazypad", options=api.TrainOptions(
        tuple(normal[4:]), iterations_scale=scale, keep_unskilled=True))
    return [f"**CrazyPAD E8** nano-quadrotor (Masalimov K. et al., Data 2024, 9, 79, doi "
            f"10.3390/data9060079; MIT), normal flights: {len(normal[:4])} to train, "
            f"{len(normal[4:])} held out; profile crazyflie with the vertical acceleration "
            "`az` and the height `z` added. Horizon chosen: "
            f"{_horizon(result)}.", "", *_skill_table(result), "",
            *_defect_verdicts(defects, normal[4:], profile, work / "crazypad")]


def _defect_verdicts(defects: list[Path], heldout: list[Path], profile: "Profile",
                     model_dir: Path) -> list[str]:
    """Every defect flight and every held-out normal one diagnosed with the model as
    trained (uncalibrated: the profile's thresholds, raised where the held-out flights
    showed more): the verdicts as the terminal writes them, with what was judged."""
    from auvdiag_cli import api
    from auvdiag_cli.reports.json_report import verdict_title

    model = api.load_model(model_dir, profile)

    def verdicts(paths: list[Path]) -> Counter[str]:
        return Counter(verdict_title(api.build_report(api.diagnose(path, profile, model)))
                       for path in paths)

    defect, normal = verdicts(defects), verdicts(heldout)
    return [f"The {len(defects)} flights with a defect (added weights, cut propellers) and the "
            f"{len(heldout)} held-out normal flights, diagnosed with this model as trained, "
            "before calibration (the profile's thresholds, raised to 1.5 times the g of the "
            "held-out flights where that is more: those flights set them, so their column "
            "shows that they pass, not how a new normal flight fares):", "",
            "| verdict | defect flights | held-out normal flights |", "|---|---|---|",
            *(f"| {verdict} | {defect[verdict]} | {normal[verdict]} |"
              for verdict, _ in (defect + normal).most_common())]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--iterations-scale", type=float, default=1.0)
    parser.add_argument("--folds", type=int, default=5, help="Haizhe cross-validation folds")
    args = parser.parse_args()
    if args.folds < 3:
        parser.error("--folds must be at least 3 (one to judge, one to calibrate, the rest "
                     "to train)")
    if not args.data.is_dir():
        print(f"Real data not found at {args.data}: skipped (docs/results.md names the data sets).")
        return
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), "
          f"Python {platform.python_version()}; data from {args.data}.\n")
    with tempfile.TemporaryDirectory() as work:
        sections: list[tuple[str, str, Callable[[Path], list[str]]]] = [
            ("Haizhe", "haizhe/train",
             lambda f: haizhe(f, Path(work), args.iterations_scale, args.folds)),
            ("CrazyPAD", "crazypad", lambda f: crazypad(f, Path(work), args.iterations_scale)),
            ("ArduSub", "ardusub", lambda f: ardusub(f, Path(work), args.iterations_scale))]
        for name, sub, section in sections:
            folder = args.data / sub
            if not folder.is_dir():
                print(f"{name}: not found at {folder}: skipped.\n")
                continue
            print("\n".join(section(folder)) + "\n")


if __name__ == "__main__":
    main()
