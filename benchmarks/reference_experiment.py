"""The paper's reference experiment and the fault cases around it, over several seeds.

Simulates each scenario, writes it as a real ROS 2 (mcap) bag, diagnoses it with the shipped
model and prints a Markdown table: verdict, component, case, onset error and detection delay.
Usage: python benchmarks/reference_experiment.py [--seeds N]
"""

import argparse
import json
import platform
import statistics
import tempfile
import time
from datetime import date
from pathlib import Path

from auvdiag_cli import api

SCENARIOS = ["paper-flow-sensor-covered", "paper-normal", "mission-ccw", "mission-large-cw",
             "mission-fast-ccw", "routine-and-mission", "mission-thruster-0-dead",
             "mission-thruster-1-dead", "mission-yaw-rate-sensor-dead", "routine-thruster-0-dead",
             "routine-thruster-1-dead", "za-thruster-0-dead", "mission-thruster-0-weak",
             "mission-thruster-1-weak", "mission-flow-sensor-bias", "mission-yaw-rate-sensor-drift"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    profile, model = api.load_profile(), api.load_model()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for name in SCENARIOS:
            delays, onset_errors, outcomes, max_g = [], [], [], []
            for seed in range(1000, 1000 + args.seeds):
                path = Path(work) / f"{name}-{seed}"
                api.simulate(name, profile, path, log_format="ros2-mcap", seed=seed)
                truth = json.loads(path.with_name(f"{path.name}.truth.json").read_text())
                result = api.diagnose(path, profile, model)
                outcomes.append((result.verdict, result.component or "/".join(result.candidates),
                                 result.case))
                # Peak g as a fraction of its threshold: how close a normal log came to alarm.
                max_g.append(max(s.max_g[k] / s.segment.thresholds[k]
                                 for s in result.segments for k in s.max_g
                                 if s.max_g[k] == s.max_g[k]))
                if truth["fault"] and result.detected_at_s is not None:
                    delays.append(result.detected_at_s - truth["fault"]["onset_s"])
                    onset_errors.append(abs(result.onset_s - truth["fault"]["onset_s"]))
            verdicts = sorted(set(outcomes), key=str)
            rows.append((name, verdicts, delays, onset_errors, max_g))
    print(f"Measured {date.today()} on {platform.machine()} ({platform.processor() or 'cpu'}), "
          f"{args.seeds} seeds each, shipped model, ros2-mcap logs.\n")
    print("| scenario | outcome(s): verdict, component, case | detection delay s "
          "(median / worst) | onset error s (worst) |")
    print("|---|---|---|---|")
    for name, verdicts, delays, onset_errors, max_g in rows:
        outcome = "; ".join(f"{v} {c or '-'} {k}" for v, c, k in verdicts)
        delay = (f"{statistics.median(delays):.1f} / {max(delays):.1f}" if delays
                 else f"- (peak g at {100 * max(max_g):.0f} % of threshold)")
        onset = f"{max(onset_errors):.1f}" if onset_errors else "-"
        print(f"| {name} | {outcome} | {delay} | {onset} |")


if __name__ == "__main__":
    started = time.perf_counter()
    main()
    print(f"\n({time.perf_counter() - started:.0f} s)")
