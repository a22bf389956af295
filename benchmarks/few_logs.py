"""A vehicle's thresholds from the handful of normal logs a user has: a model trained on
three normal missions, its thresholds set by `calibrate` on two more, by the margin rule
(1.5 x the largest g) and to a false-alarm budget (`--false-alarm-rate 0.01`, which with
fewer than five logs fits each signal's g to blocks of them); then false alarms on ten
normal missions of other seeds, and the faults of the simulator's scenarios (each motor dead,
each motor at half its thrust, the gyro and barometer dead, all from 60 s) found and named.

The simulated quadrotor (`arducopter_quad`, DataFlash logs as ArduCopter writes them), its
hover-and-turn controller holding height, heading and the roll and pitch rates.

Usage: python benchmarks/few_logs.py > few_logs.md
"""

import argparse
import os
import platform
import tempfile
import time
from datetime import date
from pathlib import Path

PROFILE = "arducopter_quad"
TRAINING = ("paper-normal", "mission-ccw", "mission-large-cw")
CALIBRATION = ("mission-sprint-ccw", "mission-fast-cw")
NORMAL = ("paper-normal", "mission-ccw", "mission-large-cw", "mission-sprint-ccw",
          "mission-fast-cw")
FAULTS = ("motor-1-dead", "motor-2-dead", "motor-3-dead", "motor-4-dead", "motor-1-weak",
          "motor-2-weak", "motor-3-weak", "motor-4-weak", "gyro-dead", "barometer-dead")
TRAINING_SEED, CALIBRATION_SEED, NORMAL_SEEDS, FAULT_SEED = 1, 2, (11, 12), 21


def _flown(work: Path, scenario: str, seed: int) -> Path:
    from auvdiag_cli import api

    path = work / f"{scenario}-{seed}.bin"
    if not path.exists():
        api.simulate(scenario, api.load_profile(PROFILE), path, log_format="bin", seed=seed)
    return path


def _judged(model_dir: Path, calibration: list[Path], budgeted: bool,
            normal: list[Path], faulty: dict[str, Path]) -> tuple[str, ...]:
    from auvdiag_cli import api

    profile = api.load_profile(PROFILE)
    model = api.load_model(model_dir, profile)
    options = (api.CalibrateOptions(budget=api.FalseAlarmBudget(0.01)) if budgeted
               else api.CalibrateOptions())
    result = api.calibrate(calibration, profile, model, options=options)
    alarms = sum(api.diagnose(p, profile, model).verdict.value == "fault" for p in normal)
    found = named = 0
    for scenario, path in faulty.items():
        diagnosis = api.diagnose(path, profile, model)
        found += diagnosis.verdict.value == "fault" and (diagnosis.onset_s or 0.0) >= 55.0
        part = scenario.rsplit("-", 1)[0].replace("-", "_")
        named += diagnosis.component == part
    shown = ", ".join(f"{name} {mode.thresholds[name]:g} %" for mode in result.modes
                      for name in mode.evidence) or "none judged"
    label = ("to a budget of 1 % (g from blocks of the logs)" if budgeted
             else "margin rule (1.5 x the largest g)")
    return (label, shown, f"{alarms}/{len(normal)}", f"{found}/{len(faulty)}",
            f"{named}/{len(faulty)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args()
    from auvdiag_cli import api

    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        training = [_flown(work, s, TRAINING_SEED) for s in TRAINING]
        calibration = [_flown(work, s, CALIBRATION_SEED) for s in CALIBRATION]
        normal = [_flown(work, s, seed) for seed in NORMAL_SEEDS for s in NORMAL]
        faulty = {f: _flown(work, f"mission-{f}", FAULT_SEED) for f in FAULTS}
        api.train(training, api.load_profile(PROFILE), work / "model")
        rows = [_judged(work / "model", calibration, budgeted, normal, faulty)
                for budgeted in (False, True)]
    minutes = (time.perf_counter() - started) / 60
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), Python "
          f"{platform.python_version()}, in {minutes:.1f} min: `{PROFILE}` trained on "
          f"{len(TRAINING)} normal missions (seed {TRAINING_SEED}), calibrated on "
          f"{len(CALIBRATION)} more (seed {CALIBRATION_SEED}); {len(normal)} normal missions of "
          f"seeds {', '.join(map(str, NORMAL_SEEDS))} and {len(faulty)} faults from 60 s "
          f"(seed {FAULT_SEED}: each motor dead, each at half its thrust, the gyro and the "
          "barometer dead) diagnosed.\n")
    print("| thresholds | g thresholds of the judged signals | normal missions alarmed "
          "| faults found after 55 s | the part named |")
    print("|---|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
