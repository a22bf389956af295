"""auvdiag on real failures that start mid-flight: the ALFA fixed-wing flights.

Data (read from ../shared/data/alfa, or --data; skipped with a message when absent): ALFA,
Keipour A., Mousaei M., Scherer S., "ALFA: A dataset for UAV fault and anomaly detection",
IJRR 40(2-3), 2021 (doi 10.1177/0278364920966642; data doi 10.1184/R1/12707963), its
processed sequences as per-topic CSV folders with `labels.csv` (kind and onset per sequence).

Leave one flying day out: for each day, a model is trained with the shipped
`arduplane_carbonz` profile on the other days' normal flights and on the part of their
failed flights before the failure (`train --healthy`, the part ending --guard seconds
before the onset), calibrated on the same logs with `--false-alarm-rate 0.05`, and every
flight of the day left out is diagnosed as it is (its CSV folder): with the profile as
shipped (every signal judged against the flight's own beginning, by the change test) and,
beside it, with the replay judging across flights as well each signal the profile marks
`own_log_only` (the same model, calibrated so). A failed flight is found when the verdict
is a fault detected at or after the onset; a detection before the onset, or any fault on a
flight without failure, is a false alarm. The published figures beside them
are the recursive-least-squares detector of Keipour, Mousaei and Scherer, "Automatic
real-time anomaly detection for autonomous aerial vehicles", ICRA 2019, on 22 of these
flights. Then each day's flights alone train and calibrate a model that judges the other
days' flights: the handful of logs a user has after one day of flying.

Usage: python benchmarks/alfa.py [--data DIR] [--iterations-scale 1.0] [--guard 1.0]
                                [--keep DIR]
"""

import argparse
import csv
import os
import platform
import statistics
import tempfile
import time
from collections import defaultdict
from dataclasses import dataclass, field
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING

from alfa_roll import roll_after_failure

if TYPE_CHECKING:
    from auvdiag_cli.engine.results import Diagnosis
    from auvdiag_cli.jobs.train import HorizonScore
    from auvdiag_cli.vehicle.profile import Profile
    from models.store import LoadedModel

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "alfa"
FALSE_ALARM_RATE = 0.05
GOAL_DELAYS_S = (2.0, 6.0)      # the goal's median and worst detection delay
# Keipour et al., ICRA 2019, Table II: per kind, average detection delay (s).
PUBLISHED_DELAY_S = {"engine": 2.28, "rudder": 0.21, "elevator": 0.36, "aileron": 3.31}
# The part a failure of each kind should be named as (the profile's actuators).
EXPECTED_PART = {"engine": {"engine"}, "aileron": {"ailerons"}, "elevator": {"elevator"},
                 "rudder": {"rudder"}, "aileron+rudder": {"ailerons", "rudder"}}
PUBLISHED_SUMMARY = ("published RLS detector (22 flights): precision 88.2 %, recall 88.2 %, "
                     "detection 2.02 s on average, 5.6 s at worst")


@dataclass(frozen=True)
class Flight:
    folder: Path
    kind: str            # normal, engine, aileron, elevator, rudder, aileron+rudder
    onset_ns: int | None

    @property
    def day(self) -> str:
        return self.folder.name.split("_")[1][:10]


@dataclass(frozen=True)
class Outcome:
    flight: Flight
    verdict: str
    detected_s: float | None     # after the log's start
    onset_s: float | None        # the true onset, after the log's start
    component: str | None
    judge: str | None            # which judge's alarm made the verdict
    # The change test's statistics, (statistic, signal) -> largest before the onset (the
    # whole flight without one) and after it.
    peaks_before: dict[tuple[str, str], float] = field(default_factory=dict)
    peaks_after: dict[tuple[str, str], float] = field(default_factory=dict)
    # The same within each of GOAL_DELAYS_S of the onset.
    peaks_soon: dict[float, dict[tuple[str, str], float]] = field(default_factory=dict)
    # Where the change test's alarm made the verdict: its onset and the error it stated,
    # and the signal (or a part's signature) furthest over its threshold at the alarm.
    stated_onset: tuple[float, float] | None = None
    crossed: str | None = None

    @property
    def named_right(self) -> bool:
        return self.found and self.component in EXPECTED_PART.get(self.flight.kind, set())

    @property
    def alarmed(self) -> bool:
        return self.verdict == "fault"

    @property
    def early(self) -> bool:
        """A detection before the failure began: a false alarm."""
        return self.alarmed and self.onset_s is not None and self.detected_s is not None \
            and self.detected_s < self.onset_s

    @property
    def found(self) -> bool:
        return self.alarmed and self.onset_s is not None and not self.early

    @property
    def delay_s(self) -> float | None:
        if not self.found or self.detected_s is None or self.onset_s is None:
            return None
        return self.detected_s - self.onset_s


def flights(data: Path) -> list[Flight]:
    found = []
    with (data / "labels.csv").open(newline="") as stream:
        for row in csv.DictReader(stream):
            kind = "normal" if row["kind"] in ("normal", "no_ground_truth") else row["kind"]
            onset = int(row["onset_time_ns"]) if row["onset_time_ns"] else None
            found.append(Flight(data / row["sequence"], kind, onset))
    return found


def _healthy_file(training: list[Flight], work: Path, guard_s: float) -> Path:
    path = work / "healthy.csv"
    with path.open("w", newline="") as stream:
        out = csv.writer(stream)
        out.writerow(["log", "start", "end"])
        for flight in training:
            if flight.onset_ns is not None:
                out.writerow([flight.folder.name, "", f"{flight.onset_ns / 1e9 - guard_s:.3f}"])
    return path


SHIPPED = "as shipped (every signal judged against the flight's own beginning)"
REPLAY = ("with the replay beside it (each signal the profile marks `own_log_only` judged "
          "across flights as well)")


def _own_log_only_replayed(profile: "Profile") -> "Profile":
    """The profile with no signal marked `own_log_only`: the replay judges them too."""
    from dataclasses import replace
    return replace(profile, sensors=tuple(replace(s, own_log_only=None)
                                          for s in profile.sensors))


def _judged_by(model: "LoadedModel", chosen: "HorizonScore", profile: "Profile") -> str:
    """What the change test judges once calibrated (a signal with a threshold of its own, or
    within a part's signature that has one), with its skill a moment ahead, and the
    replay's skill."""
    from auvdiag_cli.engine.change_columns import change_judged
    from auvdiag_cli.engine.change_signatures import judged_within

    replayed = [signal for signal, s in chosen.signals.items() if s.judged]
    replay = ", ".join(f"{signal} {chosen.signals[signal].skill:.2f}" for signal in replayed)
    ahead = model.card.ahead
    if ahead is None:
        return f"the replay {replay or 'none'}"
    limited = {name for limits in model.card.change_thresholds.values() for name in limits}
    candidates = change_judged(model, replayed)
    within = judged_within(profile.actuators, profile.sensors, candidates)
    judged = [signal for signal in candidates if signal in limited
              or any(s in limited for s in within.get(signal, ((), ""))[0])]
    change = ", ".join(f"{signal} {ahead.skill[signal]:.2f}" if signal in ahead.skill
                       else signal for signal in judged)
    return f"{change or 'none'} (skill a moment ahead); the replay's skill {replay or 'none'}"


def judge_flights(training: list[Flight], judged_flights: list[Flight], name: str, work: Path,
                  scale: float, guard_s: float, variants: tuple[str, ...] = (SHIPPED,)
                  ) -> tuple[dict[str, list[Outcome]], str]:
    """A model trained on ``training`` (kept as ``work``/model-``name``), calibrated on the
    same logs once per variant of the profile, judges ``judged_flights``; and what it
    judges, with the skill of each signal."""
    from shutil import copytree

    from auvdiag_cli import api

    shipped = api.load_profile("arduplane_carbonz")
    healthy = api.read_healthy_parts(_healthy_file(training, work, guard_s))
    model_dir = work / f"model-{name}"
    logs = [f.folder for f in training]
    result = api.train(logs, shipped, model_dir,
                       options=api.TrainOptions(iterations_scale=scale, healthy=healthy,
                                                keep_unskilled=True))
    judged = ""
    outcomes: dict[str, list[Outcome]] = {}
    for variant in variants:
        profile = shipped if variant == SHIPPED else _own_log_only_replayed(shipped)
        variant_dir = model_dir if variant == SHIPPED else work / f"model-{name}-replay"
        if variant_dir != model_dir:
            copytree(model_dir, variant_dir, dirs_exist_ok=True)
        model = api.load_model(variant_dir, profile)
        api.calibrate(logs, profile, model, options=api.CalibrateOptions(
            budget=api.FalseAlarmBudget.parse(str(FALSE_ALARM_RATE)), healthy=healthy))
        api.save_model(model, variant_dir)      # as calibrated, for --keep
        if variant == SHIPPED:
            judged = _judged_by(model, result.chosen, profile)
        outcomes[variant] = [_outcome(flight, api.diagnose(flight.folder, profile, model),
                                      profile) for flight in judged_flights]
    return outcomes, judged


def _outcome(flight: Flight, diagnosis: "Diagnosis", profile: "Profile") -> Outcome:
    onset_s = None if flight.onset_ns is None else (flight.onset_ns
                                                    - diagnosis.start_ns) / 1e9
    judge = _judge(diagnosis)
    change = diagnosis.change_check
    stated = (change.onset_s, change.onset_error_s) if (
        judge == "change test" and change is not None
        and change.onset_s is not None) else None
    return Outcome(flight, str(diagnosis.verdict), diagnosis.detected_at_s, onset_s,
                   diagnosis.component, judge, *_change_peaks(diagnosis, onset_s, profile),
                   stated, None if stated is None or change is None
                   else next(iter(change.flagged), None))


def _change_peaks(diagnosis: "Diagnosis", onset_s: float | None, profile: "Profile"
                  ) -> tuple[dict[tuple[str, str], float], dict[tuple[str, str], float],
                             dict[float, dict[tuple[str, str], float]]]:
    """The change test's statistics on every signal and the profile's signatures over
    them, largest before the onset, after it, and within each of GOAL_DELAYS_S of it."""
    import numpy as np

    from auvdiag_cli.engine.change_check import REFERENCE_MIN_S
    from auvdiag_cli.engine.change_signatures import below_only, signatures
    from auvdiag_cli.engine.change_statistics import change_statistics

    residual, time_s = diagnosis.histories.change_residual, diagnosis.histories.time_s
    if residual is None:
        return {}, {}, {}
    after = np.zeros(len(time_s), bool) if onset_s is None else time_s >= onset_s
    before: dict[tuple[str, str], float] = {}
    later: dict[tuple[str, str], float] = {}
    soon: dict[float, dict[tuple[str, str], float]] = {s: {} for s in GOAL_DELAYS_S}
    parts = [(~after, before), (after, later)] + [
        (after & (time_s <= (onset_s or 0.0) + delay), soon[delay]) for delay in GOAL_DELAYS_S]
    names = list(diagnosis.histories.change_names or diagnosis.histories.sensor_names)
    found = signatures(profile.actuators, names)
    for statistic, values in change_statistics(
            residual, profile.window_samples, round(REFERENCE_MIN_S / profile.dt_s),
            found, names=names,
            below_only={*(loop.name for loop in profile.tracking),
                        *below_only(profile.sensors)}).items():
        for column, name in enumerate([*names, *(s.name for s in found)]):
            for part, into in parts:
                known = values[part, column]
                if np.isfinite(known).any():
                    into[statistic, name] = float(np.nanmax(known))
    return before, later, soon


def ceiling(outcomes: list[Outcome]) -> str:
    """How many failures any thresholds could find without a false alarm: those whose
    statistics after the onset exceed the largest value every healthy stretch reached."""
    largest: dict[tuple[str, str], float] = defaultdict(float)
    for outcome in outcomes:
        for key, value in outcome.peaks_before.items():
            largest[key] = max(largest[key], value)
    failed = [o for o in outcomes if o.flight.onset_ns is not None]

    def separable(within_s: float | None) -> int:
        return sum(any(value > largest[key] for key, value in (
            o.peaks_after if within_s is None else o.peaks_soon.get(within_s, {})).items())
            for o in failed)

    soon = ", ".join(f"{separable(delay)} within {delay:g} s" for delay in GOAL_DELAYS_S)
    return (f"Separable after the fact: {separable(None)} of {len(failed)} "
            "failed flights exceed, after their onset, the largest value every healthy "
            "stretch of every flight reached in some statistic of the change test: what any "
            f"thresholds could find without a false alarm; {soon} of the onset (the goal's "
            "median and worst delay).")


def budget_expectation(outcomes: list[Outcome]) -> str:
    """How many false alarms the budget itself allows: each flight's healthy stretch (the
    whole of a normal flight, a failed one's up to its onset) is one log the thresholds
    were set to pass but for that share."""
    return (f"The budget: thresholds set to pass all but {FALSE_ALARM_RATE:.0%} of normal logs "
            f"expect about {FALSE_ALARM_RATE * len(outcomes):.1f} false alarm(s) in the "
            f"healthy stretches of {len(outcomes)} flights.")


def onset_honesty(outcomes: list[Outcome]) -> str:
    """Whether the true onset lies within what the change test stated of it."""
    stated = [(o.stated_onset, o.onset_s) for o in outcomes
              if o.found and o.stated_onset is not None and o.onset_s is not None]
    if not stated:
        return "No failure found by the change test: no onset estimate to check."
    inside = sum(abs(estimate - true) <= error for (estimate, error), true in stated)
    offsets = [estimate - true for (estimate, _), true in stated]
    errors = [error for (_, error), _ in stated]
    return (f"Onset estimated by the change test: the true onset within the stated error in "
            f"{inside} of {len(stated)} found; estimate - true onset median "
            f"{statistics.median(offsets):+.1f} s ({min(offsets):+.1f} to {max(offsets):+.1f}); "
            f"stated error median {statistics.median(errors):.1f} s.")


def _judge(diagnosis: "Diagnosis") -> str | None:
    """Which judge raised the alarm the verdict rests on."""
    if str(diagnosis.verdict) != "fault" or diagnosis.detected_at_s is None:
        return None
    change = diagnosis.change_check
    if change is not None and change.alarm_s == diagnosis.detected_at_s:
        return "change test"
    for name, check in (("effort", diagnosis.effort_check),
                        ("commands", diagnosis.command_check)):
        if check is not None and check.alarm_s == diagnosis.detected_at_s:
            return name
    return "replay"


def _seconds(values: list[float]) -> str:
    if not values:
        return "–"
    return f"{statistics.median(values):.1f} / {max(values):.1f}"


def table(outcomes: list[Outcome]) -> list[str]:
    rows = ["| kind | flights | found after onset | false alarms | delay median / worst (s) "
            "| right part named | found first by | published mean delay (s) |",
            "|---|---|---|---|---|---|---|---|"]
    by_kind: dict[str, list[Outcome]] = defaultdict(list)
    for outcome in outcomes:
        by_kind[outcome.flight.kind].append(outcome)
    for kind in sorted(by_kind, key=lambda k: (k == "normal", k)):
        group = by_kind[kind]
        false_alarms = sum(o.early or (o.alarmed and o.onset_s is None) for o in group)
        judges: dict[str, int] = defaultdict(int)
        for o in group:
            if o.found:
                judges[o.judge or "?"] += 1
        rows.append(
            f"| {kind} | {len(group)} | "
            f"{'–' if kind == 'normal' else sum(o.found for o in group)} | {false_alarms} | "
            f"{_seconds([d for o in group if (d := o.delay_s) is not None])} | "
            f"{'–' if kind == 'normal' else sum(o.named_right for o in group)} | "
            f"{', '.join(f'{j} {n}' for j, n in sorted(judges.items())) or '–'} | "
            f"{PUBLISHED_DELAY_S.get(kind, '–')} |")
    return rows


def summary(outcomes: list[Outcome]) -> list[str]:
    failed = [o for o in outcomes if o.flight.onset_ns is not None]
    alarms = [o for o in outcomes if o.alarmed]
    true_alarms = [o for o in alarms if o.found]
    delays = [d for o in failed if (d := o.delay_s) is not None]
    named = sum(o.named_right for o in true_alarms)
    precision = len(true_alarms) / len(alarms) if alarms else float("nan")
    recall = len(true_alarms) / len(failed) if failed else float("nan")
    return [f"precision {precision:.1%}, recall {recall:.1%} "
            f"({len(true_alarms)} of {len(failed)} failed flights found after their onset; "
            f"{len(alarms) - len(true_alarms)} false alarm(s) in {len(outcomes)} flights), "
            f"delay median {statistics.median(delays) if delays else float('nan'):.1f} s, "
            f"worst {max(delays, default=float('nan')):.1f} s; the right part named in "
            f"{named} of {len(true_alarms)} found."]


ONE_DAY = ("**Trained on one day's flights** (the handful a user has after a day of flying: "
           "that day's normal flights and its failed flights' healthy parts, trained and "
           "calibrated on as above; or, for a day with three normal flights or more, those "
           "alone; every flight of the other days judged, as shipped):")
MIN_NORMAL_FLIGHTS = 3
AILERONS = ("**The roll after an aileron failed** (as shipped; what the motion gave any judge "
            "to see):")


def one_day_rows(every: list[Flight], work: Path, scale: float, guard_s: float) -> list[str]:
    """A table row per flying day whose flights alone train and calibrate the model."""
    rows = ["| trained on | flights | found after onset | failed flights undetermined | "
            "false alarms | normal flights undetermined | delay median / worst (s) | right "
            "part named | the change test judges |",
            "|---|---|---|---|---|---|---|---|---|"]
    days = sorted({f.day for f in every})
    # And each day with a few normal flights, those alone: what a user has who kept no
    # failed flight's healthy part.
    choices = [(day, day, [f for f in every if f.day == day]) for day in days] + [
        (f"{day}, its {len(normal)} normal flights only", f"normal-{day}", normal)
        for day in days if len(normal := [f for f in every if f.day == day
                                          and f.onset_ns is None]) >= MIN_NORMAL_FLIGHTS]
    for label, name, training in choices:
        day = training[0].day
        outcomes, judged = judge_flights(training, [f for f in every if f.day != day],
                                         f"only-{name}", work, scale, guard_s)
        found = outcomes[SHIPPED]
        failed = [o for o in found if o.flight.onset_ns is not None]
        delays = [d for o in failed if (d := o.delay_s) is not None]
        undetermined = [o for o in found if o.verdict == "undetermined"]
        rows.append(f"| {label} | {len(training)} | {sum(o.found for o in failed)} of "
                    f"{len(failed)} | {sum(o.flight.onset_ns is not None for o in undetermined)} "
                    f"| {sum(o.alarmed and not o.found for o in found)} of {len(found)} | "
                    f"{sum(o.flight.onset_ns is None for o in undetermined)} | "
                    f"{_seconds(delays)} | "
                    f"{sum(o.named_right for o in found)} | {judged} |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--iterations-scale", type=float, default=1.0)
    parser.add_argument("--guard", type=float, default=1.0,
                        help="seconds before the onset where the healthy part ends")
    parser.add_argument("--keep", type=Path, default=None,
                        help="keep each day's model and healthy parts in this folder")
    args = parser.parse_args()
    if not (args.data / "labels.csv").is_file():
        print(f"ALFA not found at {args.data}: skipped (docs/results.md names the data set).")
        return
    print(f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), "
          f"Python {platform.python_version()}; data from {args.data} (ALFA, Keipour et al. "
          "2021, doi 10.1184/R1/12707963).\n")
    every = flights(args.data)
    outcomes: dict[str, list[Outcome]] = {SHIPPED: [], REPLAY: []}
    notes = []
    with tempfile.TemporaryDirectory() as scratch:
        work = args.keep or Path(scratch)
        work.mkdir(parents=True, exist_ok=True)
        for day in sorted({f.day for f in every}):
            started = time.perf_counter()
            day_outcomes, judged = judge_flights([f for f in every if f.day != day],
                                                 [f for f in every if f.day == day], day,
                                                 work, args.iterations_scale, args.guard,
                                                 (SHIPPED, REPLAY))
            for variant, found in day_outcomes.items():
                outcomes[variant] += found
            notes.append(f"- {day} left out ({len(day_outcomes[SHIPPED])} flights): the "
                         f"change test judges {judged}; {time.perf_counter() - started:.0f} s")
        one_day = one_day_rows(every, work, args.iterations_scale, args.guard)
    print(f"Beside it, the {PUBLISHED_SUMMARY}.\n")
    for variant, found in outcomes.items():
        print(f"**{variant[0].upper()}{variant[1:]}**: " + summary(found)[0] + "\n")
        if variant == SHIPPED:
            print(budget_expectation(found) + "\n")
            print(ceiling(found) + "\n")
            print(onset_honesty(found) + "\n")
        print("\n".join(table(found)))
        print()
    print("\n".join(notes))
    print(f"\n{AILERONS}\n")
    print("\n".join(roll_after_failure(
        [(o.flight.folder, o.flight.onset_ns, o.delay_s) for o in outcomes[SHIPPED]
         if "aileron" in o.flight.kind and o.flight.onset_ns is not None])))
    print("\n".join(["", ONE_DAY, "", *one_day]))
    print("\nPer flight:\n")
    print("| flight | kind | verdict | onset (s) | detected (s) | component | judge |")
    print("|---|---|---|---|---|---|---|")
    for o in outcomes[SHIPPED]:
        def when(value: float | None) -> str:
            return "–" if value is None else f"{value:.1f}"
        print(f"| {o.flight.folder.name} | {o.flight.kind} | {o.verdict} | "
              f"{when(o.onset_s)} | {when(o.detected_s)} | {o.component or '–'} | "
              f"{o.judge or '–'}{f' ({o.crossed})' if o.crossed else ''} |")


if __name__ == "__main__":
    main()
