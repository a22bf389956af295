"""Rebuild what the project ships from simulated dives: a vehicle's model, its command
relations, its skill scores, and the sample logs with their expected reports.

    python scripts/shipped.py model [PROFILE] [--output DIR] [--format FORMAT]
    python scripts/shipped.py relate [PROFILE] [--model DIR] [--format FORMAT]
    python scripts/shipped.py score [PROFILE] [--model DIR] [--format FORMAT]
    python scripts/shipped.py samples [--output DIR]

PROFILE: twin_burger (default), three_thruster or bluerov2; the model directory defaults to
models/PROFILE (the samples' folder to sample_logs); the dives are written as ros2-mcap
(tlog for bluerov2, which is described for MAVLink logs only). About 4-5 minutes on 2 cores
for the Twin-Burger's model, 6 for three_thruster, 10 for bluerov2. Every step runs the
`auvdiag` commands a user would run (in this process), so what it does is what the
documentation describes.

The scenarios (one list, every step takes its part of it):
- the missions: rectangles of both sizes, both directions, speeds from 0.125 to 0.45 m/s;
- training: each Diagnosis Motion Sequence alone, the missions, all DMSs before a mission and
  open-loop excitation over the whole command range; seeds 1-3, seed 101 held out;
- scoring: seed 301 (never trained, held out or calibrated on), a part of the missions;
- calibration (BlueROV2 only): seeds 201-203.
"""

import argparse
import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MISSIONS = ("paper-normal", "mission-ccw", "mission-large-cw", "mission-large-ccw",
            "mission-fast-cw", "mission-fast-ccw", "mission-sprint-cw", "mission-sprint-ccw")
BEFORE_A_MISSION = "all-dms-and-mission"
EXCITATION = "excitation"
SCORED = ("paper-normal", "mission-ccw", "mission-large-cw", "mission-sprint-ccw",
          BEFORE_A_MISSION)
CALIBRATED = (BEFORE_A_MISSION, "paper-normal", "mission-large-ccw", "mission-sprint-cw")
TRAINING_SEEDS, HELD_OUT_SEED, SCORING_SEED = (1, 2, 3), 101, 301
CALIBRATION_SEEDS = (201, 202, 203)
# The sample logs: a normal and a faulty dive in every format (scenario, format, name).
SAMPLES = (
    ("paper-flow-sensor-covered", "ros2-mcap", "paper-flow-sensor-covered"),
    ("paper-normal", "ros2-mcap", "paper-normal"),
    ("routine-and-mission", "bag", "routine-and-mission.bag"),
    ("mission-thruster-0-dead", "bag", "mission-thruster-0-dead.bag"),
    ("mission-ccw", "db3", "mission-ccw-db3"),
    ("mission-yaw-rate-sensor-dead", "db3", "mission-yaw-rate-sensor-dead-db3"),
    ("mission-large-cw", "mcap", "mission-large-cw.mcap"),
    ("mission-thruster-1-dead", "mcap", "mission-thruster-1-dead.mcap"),
    ("mission-fast-ccw", "tlog", "mission-fast-ccw.tlog"),
    ("paper-flow-sensor-covered", "tlog", "paper-flow-sensor-covered-tlog.tlog"),
    ("mission-large-ccw", "bin", "mission-large-ccw.bin"),
    ("mission-yaw-rate-sensor-dead", "bin", "mission-yaw-rate-sensor-dead-bin.bin"),
)


def auvdiag(*args: str | Path, allowed: Sequence[int] = (0,), stdout: Path | None = None
            ) -> None:
    """Run one `auvdiag` command in this process (its standard output into ``stdout`` if
    given); stop on an exit status not allowed."""
    from auvdiag_cli.cli import app

    with contextlib.ExitStack() as stack:
        if stdout is not None:
            stack.enter_context(contextlib.redirect_stdout(
                stack.enter_context(stdout.open("w", encoding="utf-8"))))
        try:
            app([str(a) for a in args], standalone_mode=False)
            status = 0
        except SystemExit as done:
            status = int(done.code or 0)
    if status not in allowed:
        raise SystemExit(f"auvdiag {' '.join(map(str, args))}: exit status {status}")


class Dives:
    """Simulated dives of one profile, written into a scratch folder."""

    def __init__(self, profile: str, fmt: str, work: Path) -> None:
        self.profile, self.format, self.work = profile, fmt, work

    def write(self, scenario: str, seed: int) -> Path:
        path = self.work / f"{scenario}-s{seed}"
        if not path.exists():
            auvdiag("simulate", scenario, "--profile", self.profile, "--format", self.format,
                    "--seed", str(seed), "--output", path)
        return path

    def each(self, scenarios: Sequence[str], seeds: Sequence[int]) -> list[Path]:
        return [self.write(scenario, seed) for scenario in scenarios for seed in seeds]


def _dms_scenarios(profile: str) -> list[str]:
    """Each DMS alone (the scenarios named dms-NAME)."""
    from auvdiag_cli.simulator.scenarios import scenarios_for
    from auvdiag_cli.vehicle.profile import load_profile

    return [name for name in scenarios_for(load_profile(Path(profile)))
            if name.startswith("dms-") and name.count("-") == 1]


def build_model(dives: Dives, output: Path) -> None:
    # Full-range excitation of six motors spins the BlueROV2 far beyond anything its missions
    # do; its model learns from its DMSs (one per motor, more runs of each: they are short)
    # and missions, with a larger recurrent context trained longer, and its thresholds are
    # then calibrated on further normal dives, as a new vehicle's should be.
    bluerov2 = dives.profile == "bluerov2"
    dms_seeds = (1, 2, 3, 4, 5, 6) if bluerov2 else TRAINING_SEEDS
    others = [*MISSIONS, BEFORE_A_MISSION, *(() if bluerov2 else (EXCITATION,))]
    dms = _dms_scenarios(dives.profile)
    training = dives.each(dms, dms_seeds) + dives.each(others, TRAINING_SEEDS)
    holdout = [option for path in dives.each([*dms, *others], (HELD_OUT_SEED,))
               for option in ("--holdout", path)]
    model = dives.work / "model"
    auvdiag("train", *training, *holdout, "--profile", dives.profile, "--output", model,
            "--seed", "0", *(("--hidden", "48", "--iterations-scale", "2") if bluerov2 else ()))
    if bluerov2:
        auvdiag("calibrate", *dives.each(CALIBRATED, CALIBRATION_SEEDS), "--model", model,
                "--profile", dives.profile, "--floor-at-profile")
    score(dives, model)
    shutil.rmtree(output, ignore_errors=True)
    shutil.copytree(model, output)


def relate(dives: Dives, model: Path) -> None:
    holdout = [option for path in dives.each(MISSIONS, (HELD_OUT_SEED,))
               for option in ("--holdout", path)]
    auvdiag("relate", *dives.each(MISSIONS, TRAINING_SEEDS), *holdout, "--model", model,
            "--profile", dives.profile)


def score(dives: Dives, model: Path) -> None:
    auvdiag("score", *dives.each(SCORED, (SCORING_SEED,)), "--model", model, "--profile",
            dives.profile)


def samples(folder: Path) -> None:
    """The sample logs, each with its truth and the report the shipped model gives."""
    for old in folder.iterdir():
        shutil.rmtree(old) if old.is_dir() else old.unlink()
    for scenario, fmt, name in SAMPLES:
        log = folder / name
        auvdiag("simulate", scenario, "--seed", "1", "--format", fmt, "--output", log)
        stem = name.split(".")[0]
        auvdiag("diagnose", log, "--quiet", "--json", "-", "--truth",
                folder / f"{stem}.truth.csv", allowed=(0, 1),
                stdout=folder / f"{stem}.expected.json")


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("step", choices=("model", "relate", "score", "samples"))
    parser.add_argument("profile", nargs="?", default="twin_burger")
    parser.add_argument("--model", "--output", dest="model", type=Path, default=None)
    parser.add_argument("--format", default=None)
    args = parser.parse_args(argv)
    if args.step == "samples":
        # From the project's root, so that each report names its log as sample_logs/NAME.
        os.chdir(ROOT)
        folder = args.model or Path("sample_logs")
        folder.mkdir(parents=True, exist_ok=True)
        samples(folder)
        return
    model = args.model or ROOT / "models" / args.profile
    fmt = args.format or ("tlog" if args.profile == "bluerov2" else "ros2-mcap")
    with tempfile.TemporaryDirectory() as work:
        dives = Dives(args.profile, fmt, Path(work))
        {"model": lambda: build_model(dives, model), "relate": lambda: relate(dives, model),
         "score": lambda: score(dives, model)}[args.step]()


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    main()
