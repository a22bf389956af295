"""A vehicle's thresholds from the handful of normal logs a user has: a model trained on
three normal missions, judged as trained (the profile's thresholds, raised to what its
held-out log shows), with its thresholds set by `calibrate` on those three by the margin
rule, and on two more by the margin rule (1.5 x the largest g) and to a false-alarm budget
(`--false-alarm-rate 0.01`, which with fewer than five logs fits each signal's g to blocks
of them), and to the budget on those two and the three training logs (five logs: a law of
each judge's peaks, the training logs' in-sample g widened as `calibrate` does); then false
alarms on ten normal missions of other seeds, and every fault of the simulator's mission
scenarios (each actuator dead or at half its thrust, each sensor dead, from 60 s) found and
named; and each actuator weakened to 70 % of its thrust from 60 s (ten noise seeds), found
and named by the whole tool (motion, commands against the motion, change test, effort
shares), with the detection's delay.
"""

import argparse
import os
import platform
import statistics
import tempfile
import time
from collections import Counter
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

    from auvdiag_cli.simulator.run import SimulatedDive
    from auvdiag_cli.vehicle.profile import Profile
    from models.store import LoadedModel

VEHICLES = (("arducopter_quad", "bin"), ("bluerov2", "tlog"))
TRAINING = ("paper-normal", "mission-ccw", "mission-large-cw")
CALIBRATION = ("mission-sprint-ccw", "mission-fast-cw")
NORMAL = ("paper-normal", "mission-ccw", "mission-large-cw", "mission-sprint-ccw",
          "mission-fast-cw")
TRAINING_SEED, CALIBRATION_SEED, NORMAL_SEEDS, FAULT_SEED = 1, 2, (11, 12), 21
FAULT_FROM_S = 60.0
# Each actuator weakened this far from FAULT_FROM_S, flown with these seeds.
WEAKENED, WEAKENED_SEEDS = 0.7, tuple(range(21, 31))
# Each actuator failing late in its mission, judged as trained: (what, thrust kept, onset
# from the mission flown without the fault). A rotor or a thruster that stops seconds before
# it last works hard (the last LAST_WORK_S over which it gives its mean thrust over the
# mission or more): how a crash ends a log, where the part still works to the end, and no
# stop while it idles (a ROV's horizontal thrusters holding station at a mission's end),
# which changes nothing any log could show.
NEVER_S, MID_FLIGHT_SEED, LAST_WORK_S = 1e6, 41, 3.0
MID_FLIGHT = ((f"stopped {LAST_WORK_S:g} s before it last works at its mean thrust", 0.0,
               lambda dive, actuator: dive.last_works_s(actuator, LAST_WORK_S)),
              (f"weakened to {WEAKENED:.0%} two thirds of the way through", WEAKENED,
               lambda dive, actuator: 2 * dive.duration_s / 3))


def _flown(work: Path, vehicle: str, fmt: str, scenario: str, seed: int,
           severity: float | None = None, onset_s: float | None = None) -> Path:
    """The scenario flown once (its fault at ``severity`` of its thrust, None: as named;
    from ``onset_s``, None: as named)."""
    from auvdiag_cli import api
    from auvdiag_cli.simulator.scenarios import get_scenario

    onset = "" if onset_s is None else f"-{onset_s:g}"
    path = work / f"{vehicle}-{scenario}-{seed}-{severity}{onset}.{fmt}"
    if not path.exists():
        profile = api.load_profile(vehicle)
        api.simulate(get_scenario(scenario, profile, onset_s, severity), profile, path,
                     log_format=fmt, seed=seed)
    return path


def _weakened(vehicle: str) -> dict[str, str]:
    """Scenario -> actuator, for each actuator's weakness from 60 s."""
    return {name: part for name, part in _faults(vehicle).items() if name.endswith("-weak")}


def _fault_free(vehicle: str, scenario: str) -> "SimulatedDive":
    """The scenario's mission flown without its fault."""
    from auvdiag_cli import api
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import get_scenario

    profile = api.load_profile(vehicle)
    return simulate(get_scenario(scenario, profile, NEVER_S), profile, MID_FLIGHT_SEED)


def _mid_flight(work: Path, vehicle: str, fmt: str) -> list[str]:
    """Each actuator failing late in a mission (`MID_FLIGHT`), judged by the model as
    trained and calibrated (margin rule) on its training logs: named (a fault of that part
    detected after it began), the onset's error and the detection's delay, median / worst
    over those named."""
    from auvdiag_cli import api

    profile = api.load_profile(vehicle)
    rows = []
    for calibrated in (False, True):
        model = api.load_model(work / f"{vehicle}-model", profile)
        if calibrated:
            api.calibrate([_flown(work, vehicle, fmt, s, TRAINING_SEED) for s in TRAINING],
                          profile, model, options=api.CalibrateOptions())
        thresholds = "margin rule, the 3 training logs" if calibrated else "as trained"
        rows += [f"| `{vehicle}` | {thresholds} | {label} | "
                 f"{_failing_late(work, vehicle, fmt, model, severity, at)} |"
                 for label, severity, at in MID_FLIGHT]
    return rows


def _failing_late(work: Path, vehicle: str, fmt: str, model: "LoadedModel", severity: float,
                  at: "Callable[[SimulatedDive, int], float]") -> str:
    """One row's cells after its failure: named, named otherwise, onset error, delay."""
    from auvdiag_cli import api

    profile = api.load_profile(vehicle)
    named, errors, delays, said = 0, [], [], Counter[str]()
    weakened = _weakened(vehicle)
    for name, part in weakened.items():
        # The truth's thrusts are in command order; a part is its command's component.
        actuator = [c.component for c in profile.commands].index(part)
        onset_s = round(at(_fault_free(vehicle, name), actuator), 1)
        diagnosis = api.diagnose(_flown(work, vehicle, fmt, name, MID_FLIGHT_SEED,
                                        severity, onset_s), profile, model)
        seen = (diagnosis.verdict.value == "fault"
                and (diagnosis.detected_at_s or 0.0) >= onset_s)
        # Another part named alone, or this one among several ("a or b").
        said[diagnosis.component or " or ".join(diagnosis.candidates)] += (
            seen and diagnosis.component != part)
        if seen and diagnosis.component == part:
            named += 1
            errors.append((diagnosis.onset_s or 0.0) - onset_s)
            delays.append((diagnosis.detected_at_s or 0.0) - onset_s)
    other = ", ".join(f"{n} {c}" for n, c in said.items() if c) or "none"
    timing = (f"{statistics.median(errors):+.1f} / {max(errors, key=abs):+.1f} | "
              f"{statistics.median(delays):.1f} / {max(delays):.1f}" if delays else "– | –")
    return f"{named}/{len(weakened)} | {other} | {timing}"


def _faults(vehicle: str) -> dict[str, str]:
    """Scenario -> the failed part, for every mission scenario with a fault from 60 s."""
    from auvdiag_cli import api
    from auvdiag_cli.simulator.scenarios import scenarios_for

    return {name: scenario.fault.component
            for name, scenario in scenarios_for(api.load_profile(vehicle)).items()
            if name.startswith("mission-") and scenario.fault is not None
            and scenario.fault.onset_s == FAULT_FROM_S}


def _found_named(model: "LoadedModel", profile: "Profile", faulty: dict[Path, str]
                 ) -> tuple[int, int, int, list[float], Counter[str]]:
    """How many of the ``faulty`` logs (log -> the failed part) the model finds (a fault
    detected a second before the onset or later), how many it names, how many it names
    another part, the delays of those named, and how many it names of each part."""
    from auvdiag_cli import api

    found = named = wrong = 0
    delays = []
    by_part: Counter[str] = Counter()
    for path, part in faulty.items():
        diagnosis = api.diagnose(path, profile, model)
        seen = (diagnosis.verdict.value == "fault"
                and (diagnosis.detected_at_s or 0.0) >= FAULT_FROM_S - 1.0)
        found += seen
        wrong += seen and diagnosis.component not in (None, part)
        if seen and diagnosis.component == part:
            named += 1
            by_part[part] += 1
            delays.append((diagnosis.detected_at_s or 0.0) - FAULT_FROM_S)
    return found, named, wrong, delays, by_part


def _judged(vehicle: str, model_dir: Path, calibration: list[Path], label: str,
            budgeted: bool, normal: list[Path], faulty: dict[Path, str],
            weakened: dict[Path, str]) -> tuple[str, ...]:
    from auvdiag_cli import api
    from auvdiag_cli.engine.judging import replay_judged

    profile = api.load_profile(vehicle)
    model = api.load_model(model_dir, profile)
    options = (api.CalibrateOptions(budget=api.FalseAlarmBudget(0.01)) if budgeted
               else api.CalibrateOptions())
    if calibration:
        result = api.calibrate(calibration, profile, model, options=options)
        shown = ", ".join(f"{name} {mode.thresholds[name]:g} %" for mode in result.modes
                          for name in mode.evidence) or "none judged"
    else:       # as trained: the profile's thresholds, raised to what its held-out log shows
        mission = (model.card.thresholds or profile.thresholds)["mission"]
        shown = ", ".join(f"{name} {mission[name]:g} %"
                          for name in replay_judged(model, profile)) or "none judged"
    verdicts = Counter(api.diagnose(p, profile, model).verdict.value for p in normal)
    found, named, _, _, _ = _found_named(model, profile, faulty)
    weak_found, weak_named, weak_wrong, delays, by_part = _found_named(model, profile,
                                                                      weakened)
    delay = (f"{statistics.median(delays):.1f} / {max(delays):.1f}" if delays else "–")
    return (f"`{vehicle}`", label, shown, f"{verdicts['fault']}/{len(normal)}",
            f"{verdicts['undetermined']}/{len(normal)}",
            f"{found}/{len(faulty)}", f"{named}/{len(faulty)}",
            f"{weak_found}/{len(weakened)}", f"{weak_named}/{len(weakened)}",
            f"{weak_wrong}/{len(weakened)}", delay,
            ", ".join(f"{part} {by_part[part]}/{len(WEAKENED_SEEDS)}"
                      for part in dict.fromkeys(weakened.values())))


def _rows(work: Path, vehicle: str, fmt: str) -> list[tuple[str, ...]]:
    from auvdiag_cli import api

    def flown(scenario: str, seed: int) -> Path:
        return _flown(work, vehicle, fmt, scenario, seed)

    training = [flown(s, TRAINING_SEED) for s in TRAINING]
    calibration = [flown(s, CALIBRATION_SEED) for s in CALIBRATION]
    # The normal missions, and the weakened missions' own paper mission without its fault.
    normal = [*(flown(s, seed) for seed in NORMAL_SEEDS for s in NORMAL),
              *(flown("paper-normal", seed) for seed in WEAKENED_SEEDS)]
    faulty = {flown(name, FAULT_SEED): part for name, part in _faults(vehicle).items()}
    weakened = {_flown(work, vehicle, fmt, name, seed, WEAKENED): part
                for name, part in _weakened(vehicle).items() for seed in WEAKENED_SEEDS}
    model = work / f"{vehicle}-model"
    api.train(training, api.load_profile(vehicle), model)
    # As trained (the three logs a user may have, and nothing more); the margin rule on
    # those three (calibrate widens their in-sample g); the margin rule and the budget on
    # the two new logs; the budget on the training logs as well (five: a law of each
    # judge's peaks).
    ways: list[tuple[str, list[Path], bool]] = [
        ("as trained (no calibration: the profile's, raised to 1.5 x the held-out log's g)",
         [], False),
        ("margin rule (1.5 x the largest g), the 3 training logs", training, False),
        ("margin rule (1.5 x the largest g), 2 logs", calibration, False),
        ("to a budget of 1 %, 2 logs (g from blocks of them)", calibration, True),
        ("to a budget of 1 %, these and the 3 training logs", [*training, *calibration], True)]
    return [_judged(vehicle, model, logs, label, budgeted, normal, faulty, weakened)
            for label, logs, budgeted in ways]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args()
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        rows = [row for vehicle, fmt in VEHICLES for row in _rows(Path(folder), vehicle, fmt)]
        mid_flight = [row for vehicle, fmt in VEHICLES
                      for row in _mid_flight(Path(folder), vehicle, fmt)]
    minutes = (time.perf_counter() - started) / 60
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), Python "
          f"{platform.python_version()}, in {minutes:.1f} min: each vehicle trained on "
          f"{len(TRAINING)} normal missions (seed {TRAINING_SEED}), judged as trained, "
          f"calibrated on those, or on {len(CALIBRATION)} more (seed {CALIBRATION_SEED}); "
          f"{len(NORMAL) * len(NORMAL_SEEDS)} normal missions of seeds "
          f"{', '.join(map(str, NORMAL_SEEDS))}, the paper mission without a fault of each "
          "seed its actuators are weakened on (below), and every fault of its mission "
          "scenarios "
          f"from {FAULT_FROM_S:.0f} s (seed {FAULT_SEED}: each actuator dead or at half its "
          "thrust, each sensor dead) diagnosed, and each actuator weakened to "
          f"{WEAKENED:.0%} of its thrust from {FAULT_FROM_S:.0f} s (seeds "
          f"{', '.join(map(str, WEAKENED_SEEDS))}); found: a fault detected "
          f"{FAULT_FROM_S - 1:.0f} s or later (earlier, a false alarm), named: found and "
          "that part named (another named: found, and another part named alone); the "
          "delay: from the weakness's onset to its detection, median / worst over those "
          "named.\n")
    print("| vehicle | thresholds | g thresholds of the judged signals | normal missions "
          "alarmed | normal missions undetermined | faults found | the part named | "
          f"weakened to {WEAKENED:.0%}: found | named | another named | delay (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row[:-1]) + " |")
    print(f"\nWeakened to {WEAKENED:.0%}, named per actuator (of {len(WEAKENED_SEEDS)} seeds):\n")
    for row in rows:
        print(f"- {row[0]}, {row[1]}: {row[-1]}")
    print(f"\nFailing late in a mission (seed {MID_FLIGHT_SEED}; each actuator in turn, judged "
          "as trained and calibrated by the margin rule on the 3 training logs (the change "
          "test judges then); named: a fault of that part detected after it began; the onset "
          "estimated less the true one and the detection's delay, median / worst over those "
          "named):\n")
    print("| vehicle | thresholds | failure | named | named otherwise (another part, or among "
          "several) | onset error (s) | delay (s) |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(mid_flight))


if __name__ == "__main__":
    main()
