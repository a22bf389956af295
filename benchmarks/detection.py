"""Detection quality over a scenario matrix, the learned model against a linear baseline.

Matrix (Twin-Burger): every fault kind (flow sensor covered, flow bias +0.1 m/s, yaw-rate
sensor dead, yaw-rate drift 0.005 rad/s per s, each thruster dead, each thruster at 50 %),
onset at three phases of the mission found on the healthy run (on a straight, in a turn, at
low speed just after a turn as in the paper), on four missions (4 x 2 m and 5 x 2.5 m, both
directions), --seeds noise seeds; plus the same missions without a fault (--normal-seeds
seeds each) and, for thruster isolation, each thruster dead during ZA with ZB/ZC following.
Every dive is written as a real log (standalone MCAP) and diagnosed twice:
  learned   the shipped recurrent model (the tool as it runs);
  baseline  the same pipeline (segments, g, thresholds, pattern table) with the model's
            free run replaced by a linear one, x(k+1) = A x(k) + B c(k) + d, fitted by least
            squares on normal dives of other seeds.
Prints, per detector: detection rate, isolation (component exact; candidates contain the
truth), false alarms per hour of normal logs, detection delay (median, 95th pct, worst).

Usage: python benchmarks/detection.py [--seeds 2] [--normal-seeds 6] [--json PATH]
"""

import argparse
import json
import platform
import sys
import tempfile
import time
from dataclasses import dataclass
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from models.baselines import LinearDynamics
from models.baselines import fit_linear as fit_linear_model

if TYPE_CHECKING:
    from auvdiag_cli.engine.resample import AlignedFrame
    from auvdiag_cli.simulator.scenarios import Scenario
    from auvdiag_cli.vehicle.profile import Profile
    from models.normaliser import Normaliser
    from models.store import LoadedModel

FAULT_KINDS = [("flow_sensor", "covered", 0.0), ("flow_sensor", "bias", 0.1),
               ("yaw_rate_sensor", "dead", 0.0), ("yaw_rate_sensor", "drift", 0.005),
               ("thruster_0", "dead", 0.0), ("thruster_1", "dead", 0.0),
               ("thruster_0", "weak", 0.5), ("thruster_1", "weak", 0.5)]
MISSIONS = {"4x2-cw": {}, "4x2-ccw": {"clockwise": False},
            "5x2_5-cw": {"length_m": 5.0, "width_m": 2.5},
            "5x2_5-ccw": {"length_m": 5.0, "width_m": 2.5, "clockwise": False}}


def baseline_model(learned: "LoadedModel", frames: list["AlignedFrame"]) -> "LoadedModel":
    """A model directory's worth of baseline: the learned model's signals and entries (a
    copy: calibration writes into it) with every signal read from the linear model."""
    from dataclasses import replace

    from models.store import LINEAR_KEY

    baseline = learned.with_entries(
        predictors={"per_signal": dict.fromkeys(learned.sensor_names, "linear")})
    return replace(baseline, path="linear baseline",
                   extra={LINEAR_KEY: fit_linear(frames, learned.normaliser).weights})


def fit_linear(frames: list["AlignedFrame"], normaliser: "Normaliser") -> LinearDynamics:
    scale_c, scale_x = np.asarray(normaliser.command_scale), np.asarray(normaliser.state_scale)
    return fit_linear_model([f.commands / scale_c for f in frames],
                            [f.sensors / scale_x for f in frames])


def phase_times(truth_csv: Path) -> dict[str, float]:
    """Onset times on the healthy run: mid-straight, mid-turn, and low speed after a turn."""
    import pandas as pd

    truth = pd.read_csv(truth_csv)
    late = truth[truth["t_s"] > 40.0]
    turning = late[late["yaw_rate_rps"].abs() > 0.15]
    straight = late[(late["yaw_rate_rps"].abs() < 0.03) & (late["surge_mps"] > 0.1)]
    after_turn = late[(late["t_s"] > turning["t_s"].iloc[0] + 3.0)
                      & (late["surge_mps"] < 0.06) & (late["yaw_rate_rps"].abs() < 0.1)]
    return {"straight": float(straight["t_s"].iloc[len(straight) // 2]),
            "turn": float(turning["t_s"].iloc[len(turning) // 2]),
            "low-speed": float(after_turn["t_s"].iloc[0])}


@dataclass
class Case:
    name: str
    scenario: "Scenario"
    seed: int
    truth: str | None          # the failed component; None for a normal dive
    onset_s: float | None
    has_zb_zc: bool


def build_cases(profile: "Profile", seeds: int, normal_seeds: int, workdir: Path
                ) -> list[Case]:
    from auvdiag_cli import api
    from auvdiag_cli.simulator.faults import Fault
    from auvdiag_cli.simulator.scenarios import DMS_ALL, PAPER_MISSION, Scenario, _mission

    cases = []
    for mission, spec in MISSIONS.items():
        phases = _mission(**spec)  # type: ignore[arg-type]
        healthy = Scenario(f"{mission}", "normal", phases)
        probe = workdir / f"probe-{mission}.mcap"
        api.simulate(healthy, profile, probe, log_format="mcap", seed=0)
        times = phase_times(probe.with_name(f"probe-{mission}.truth.csv"))
        for seed in range(1, normal_seeds + 1):
            cases.append(Case(f"{mission} normal", healthy, 1000 + seed, None, None, False))
        for component, kind, severity in FAULT_KINDS:
            for phase, onset in times.items():
                fault = Fault(component, kind, onset, severity)
                scenario = Scenario(f"{mission}-{component}-{kind}-{phase}", "fault", phases,
                                    fault)
                for seed in range(1, seeds + 1):
                    cases.append(Case(f"{component} {kind}, {phase}", scenario, 2000 + seed,
                                      component, onset, False))
    for component in ("thruster_0", "thruster_1"):
        scenario = Scenario(f"routine-{component}", "fault", DMS_ALL + PAPER_MISSION,
                            Fault(component, "dead", 10.0))
        for seed in range(1, seeds + 1):
            cases.append(Case(f"{component} dead in ZA, ZB/ZC follow", scenario, 3000 + seed,
                              component, 10.0, True))
    return cases


def diagnose_case(case: Case, profile: "Profile", models: dict[str, "LoadedModel"],
                  workdir: Path) -> dict[str, Any]:
    from auvdiag_cli import api

    path = workdir / "case.mcap"
    path.unlink(missing_ok=True)
    dive = api.simulate(case.scenario, profile, path, log_format="mcap", seed=case.seed)
    result: dict[str, Any] = {"case": case.name, "truth": case.truth,
                              "hours": dive.duration_s / 3600}
    for name, model in models.items():
        d = api.diagnose(path, profile, model)
        named = d.component or (d.degradation.component if d.degradation else None)
        result[name] = {"fault": d.verdict == "fault", "component": named,
                        "candidates": d.candidates,
                        "delay_s": (d.detected_at_s - case.onset_s
                                    if d.detected_at_s is not None and case.onset_s is not None
                                    else None)}
    return result


def score(results: list[dict], detector: str, zb_zc_cases: set[str]) -> dict:
    faulty = [r for r in results if r["truth"] is not None]
    normal = [r for r in results if r["truth"] is None]
    # An alarm before the fault began is a false alarm, not a detection.
    detected = [r for r in faulty if r[detector]["fault"] and r[detector]["delay_s"] >= 0]
    early = [r for r in faulty if r[detector]["fault"] and r[detector]["delay_s"] < 0]
    delays = np.array([r[detector]["delay_s"] for r in detected])
    exact = [r for r in detected if r[detector]["component"] == r["truth"]]
    contains = [r for r in detected if r[detector]["component"] == r["truth"]
                or r["truth"] in r[detector]["candidates"]]
    sensors = [r for r in faulty if "sensor" in r["truth"]]
    thrusters_with_dms = [r for r in faulty if r["case"] in zb_zc_cases]
    hours = sum(r["hours"] for r in normal)
    alarms = sum(r[detector]["fault"] for r in normal)
    return {
        "faulty_logs": len(faulty), "normal_logs": len(normal), "normal_hours": hours,
        "detection_rate": len(detected) / len(faulty),
        "isolation_exact": len(exact) / len(faulty),
        "isolation_contains": len(contains) / len(faulty),
        "sensors_isolated": sum(r[detector]["component"] == r["truth"] for r in sensors)
        / max(1, len(sensors)),
        "thrusters_isolated_with_zb_zc": sum(r[detector]["component"] == r["truth"]
                                             for r in thrusters_with_dms)
        / max(1, len(thrusters_with_dms)),
        "false_alarms": alarms, "false_alarms_per_hour": alarms / hours if hours else None,
        "alarms_before_the_fault": len(early),
        "delay_median_s": float(np.median(delays)) if delays.size else None,
        "delay_p95_s": float(np.percentile(delays, 95)) if delays.size else None,
        "delay_worst_s": float(delays.max()) if delays.size else None,
        "missed": sorted({r["case"] for r in faulty if r not in detected}),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--normal-seeds", type=int, default=6)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--from-json", type=Path,
                        help="Print the table of an earlier run's --json output.")
    args = parser.parse_args()
    if args.from_json:
        saved = json.loads(args.from_json.read_text())
        print(render(saved["scores"], saved["seconds"]))
        return

    from auvdiag_cli import api
    from auvdiag_cli.engine.ingest import ingest

    started = time.perf_counter()
    profile = api.load_profile()
    learned = api.load_model()
    workdir = Path(tempfile.mkdtemp(prefix="auvdiag-detection-"))
    training, training_paths = [], []
    for scenario in ("paper-normal", "mission-ccw", "mission-large-cw", "all-dms-and-mission",
                     "excitation"):
        path = workdir / f"train-{scenario}.mcap"
        api.simulate(scenario, profile, path, log_format="mcap", seed=7)
        training.append(ingest(path, profile).frame)
        training_paths.append(path)
    baseline = baseline_model(learned, training)
    # Its residuals are larger than the learned model's: give it thresholds of its own,
    # calibrated (margin 1.5) on the normal dives it was fitted on, as a user would.
    api.calibrate(training_paths[:4], profile, baseline, options=api.CalibrateOptions(1.5))
    models = {"learned": learned, "baseline": baseline}
    cases = build_cases(profile, args.seeds, args.normal_seeds, workdir)
    results = []
    for number, case in enumerate(cases, 1):
        results.append(diagnose_case(case, profile, models, workdir))
        if number % 20 == 0:
            print(f"  {number}/{len(cases)} logs", file=sys.stderr, flush=True)
    zb_zc = {c.name for c in cases if c.has_zb_zc}
    scores = {name: score(results, name, zb_zc) for name in models}
    print(render(scores, time.perf_counter() - started))
    if args.json:
        args.json.write_text(json.dumps({"scores": scores, "results": results,
                                         "seconds": time.perf_counter() - started,
                                         "date": str(date.today())}, indent=2, default=str))


def render(scores: dict, seconds: float) -> str:
    learned, base = scores["learned"], scores["baseline"]

    def pct(value: float) -> str:
        return f"{100 * value:.0f} %"

    def s(value: float | None) -> str:
        return "-" if value is None else f"{value:.1f} s"

    def ratio(a: float | None, b: float | None) -> str:
        return "-" if not a or not b else f"{a / b:.2f}"

    rows = [(label, pct(learned[key]), pct(base[key]), ratio(learned[key], base[key]))
            for label, key in (("detection rate", "detection_rate"),
                               ("component named exactly", "isolation_exact"),
                               ("truth among the candidates", "isolation_contains"),
                               ("sensor faults isolated", "sensors_isolated"),
                               ("thrusters isolated when ZB/ZC exist",
                                "thrusters_isolated_with_zb_zc"))]
    rows += [("faulty logs alarmed before the fault began",
              str(learned["alarms_before_the_fault"]), str(base["alarms_before_the_fault"]),
              "-"),
             ("false alarms per hour of normal logs",
              f"{learned['false_alarms_per_hour']:.2f} ({learned['false_alarms']})",
              f"{base['false_alarms_per_hour']:.2f} ({base['false_alarms']})", "-"),
             ("detection delay median / 95 % / worst",
              f"{s(learned['delay_median_s'])} / {s(learned['delay_p95_s'])} / "
              f"{s(learned['delay_worst_s'])}",
              f"{s(base['delay_median_s'])} / {s(base['delay_p95_s'])} / "
              f"{s(base['delay_worst_s'])}",
              f"{ratio(learned['delay_p95_s'], base['delay_p95_s'])} (95 %)")]
    lines = [f"Measured {date.today()} on {platform.machine()}: {learned['faulty_logs']} faulty "
             f"and {learned['normal_logs']} normal logs ({learned['normal_hours']:.2f} h), "
             f"{seconds:.0f} s.", "",
             "| | learned model | linear baseline | learned / baseline |", "|---|---|---|---|"]
    lines += [f"| {name} | {a} | {b} | {r} |" for name, a, b, r in rows]
    if learned["missed"] or base["missed"]:
        lines += ["", f"Missed by the learned model: {', '.join(learned['missed']) or 'none'}. "
                  f"Missed by the baseline: {', '.join(base['missed']) or 'none'}."]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
