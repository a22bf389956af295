"""The effort check with four normal logs, where a propeller cut raises its rotor's share
near the threshold: how many such logs are found, how many the few normal logs cannot rule
out (undetermined, the rotor the candidate), and what becomes of normal logs.

The shares are drawn as a user's real ArduCopter quad X gave them (four normal flights,
motor_1 to motor_4 at 0.985 ± 0.018, 1.002 ± 0.013, 1.013 ± 0.028, 1.000 ± 0.036;
two flights with motor_1's propeller cut by 20-25 mm at 1.092 / 0.949 / 0.971 / 0.988 and
1.085 / 0.950 / 1.012 / 0.952): each draw learns an effort model from four normal logs of
rotors hovering near half throttle (the `arducopter_quad` profile's rotor group), each log's
trim drawn with those spreads, then judges the two cut logs and three more normal ones.
Simulated: the real flights are not here; the spreads and departures are theirs.

Usage: python benchmarks/effort_band.py [--draws 200] > effort_band.md
"""

import argparse
import os
import platform
from dataclasses import dataclass, field
from datetime import date
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.effort_check import EffortCheck, check_effort
from auvdiag_cli.vehicle.profile import Profile, load_profile
from models.effort_model import EffortLog, EffortModel, learn_effort
from models.effort_thresholds import MOST_LOGS_SAID

NORMAL_SHARES = np.array([0.985, 1.002, 1.013, 1.000])
NORMAL_SPREAD = np.array([0.018, 0.013, 0.028, 0.036])
CUT_SHARES = (np.array([1.092, 0.949, 0.971, 0.988]), np.array([1.085, 0.950, 1.012, 0.952]))
CUT_ROTOR = "motor_1"
NORMAL_LOGS, GOOD_LOGS = 4, 3
STEPS = 1200                       # 120 s at 10 Hz
STEP_NOISE = 0.06                  # of each rotor's command, step to step


def _commands(rng: np.random.Generator, shares: np.ndarray) -> np.ndarray:
    """Four rotors hovering near half throttle, carrying these shares."""
    level = 0.5 + 0.03 * np.sin(np.arange(STEPS) / 80.0)
    return level[:, None] * shares * (1 + rng.normal(0, STEP_NOISE, (STEPS, 4)))


def _normal(rng: np.random.Generator) -> np.ndarray:
    return _commands(rng, NORMAL_SHARES * (1 + rng.normal(0, NORMAL_SPREAD)))


def _model(profile: Profile, logs: list[np.ndarray]) -> EffortModel:
    model, _ = learn_effort(profile.effort_groups, [
        EffortLog(f"normal-{i}", c, np.ones(STEPS, bool), profile.command_names)
        for i, c in enumerate(logs)], profile.dt_s)
    assert model is not None
    return model


def _judge(profile: Profile, model: EffortModel, commands: np.ndarray) -> EffortCheck:
    return check_effort(model, profile, commands, np.ones(STEPS, bool),
                        profile.dt_s * np.arange(STEPS))


@dataclass
class Tally:
    found: int = 0          # alarmed, the cut rotor named alone
    other: int = 0          # alarmed otherwise
    not_ruled_out: int = 0  # undetermined, the cut rotor the candidate
    judged: int = 0
    # Of those not ruled out: how many normal logs like the model's would judge each
    # (`EffortCheck.judged_with_logs`; None: more than the tool says).
    logs_needed: list[int | None] = field(default_factory=list)

    def add(self, check: EffortCheck, rotor: str | None) -> None:
        self.judged += 1
        if check.suspects:
            named = rotor is not None and check.named == (rotor,)
            self.found += named
            self.other += not named
        elif check.not_ruled_out is not None and (rotor is None
                                                  or check.not_ruled_out == rotor):
            self.not_ruled_out += 1
            self.logs_needed.append(check.judged_with_logs)

    def needed(self) -> str:
        """Median and range of the normal logs said to judge those not ruled out."""
        if not self.logs_needed:
            return "–"
        said = sorted(n for n in self.logs_needed if n is not None)
        beyond = len(self.logs_needed) - len(said)
        more = f"; more than {MOST_LOGS_SAID}: {beyond}" if beyond else ""
        return (f"{int(np.median(said))} ({said[0]}-{said[-1]}){more}" if said
                else f"more than {MOST_LOGS_SAID}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=200)
    args = parser.parse_args()
    profile = load_profile(Path("arducopter_quad"))
    cut, good = Tally(), Tally()
    for seed in range(args.draws):
        rng = np.random.default_rng(seed)
        model = _model(profile, [_normal(rng) for _ in range(NORMAL_LOGS)])
        for shares in CUT_SHARES:
            cut.add(_judge(profile, model, _commands(rng, shares)), CUT_ROTOR)
        for _ in range(GOOD_LOGS):
            good.add(_judge(profile, model, _normal(rng)), None)
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), Python "
          f"{platform.python_version()}: {args.draws} draws of {NORMAL_LOGS} normal logs each "
          "(the shares and spreads of a real ArduCopter quad X's flights, simulated), "
          "budget 1 % a log.\n")
    print("| logs | judged | found, motor_1 named | alarmed otherwise | undetermined: not "
          "ruled out | normal logs like those four that would judge them, median (range) |")
    print("|---|---|---|---|---|---|")
    for label, tally in ((f"propeller of {CUT_ROTOR} cut 20-25 mm", cut), ("normal", good)):
        print(f"| {label} | {tally.judged} | {tally.found} | {tally.other} | "
              f"{tally.not_ruled_out} | {tally.needed()} |")


if __name__ == "__main__":
    main()
