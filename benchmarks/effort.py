"""The effort each actuator carries: detection and naming of a weak propeller or thruster
from each actuator's share of its group's effort, on a real quadrotor and on the simulated
BlueROV2, and false alarms on normal logs.

- CrazyPAD (Masalimov K. et al., "CrazyPAD: A Dataset for Assessing the Impact of
  Structural Defects on Nano-Quadcopter Performance", Data 2024, 9, 79, doi
  10.3390/data9060079; MIT), series E8, read from ../shared/data/crazypad (or --data) with
  the `crazyflie` profile: the effort model is learnt from the normal flights only; each
  normal flight is judged by a model learnt from the other normal flights (leave one out),
  every defective flight by the model of all normal flights. No defect label is used.
- Simulated BlueROV2 (`bluerov2` profile, its turn-then-go controller holding heading,
  speed and depth) and simulated quadrotor (`arducopter_quad`, its hover-and-turn
  controller holding height, heading and the roll and pitch rates): the effort model learnt
  from normal missions, judged on normal missions of other noise seeds and on the missions
  with one thruster or rotor weakened to 50-90 % of its thrust from 60 s, and to 70 % on
  missions of ten more noise seeds.

Usage: python benchmarks/effort.py [--data DIR] > effort.md
"""

import argparse
import csv
import functools
import itertools
import os
import platform
import tempfile
from collections import defaultdict
from datetime import date
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.effort_check import EffortCheck, check_effort
from auvdiag_cli.engine.effort_spans import smallest_later_rise
from auvdiag_cli.engine.effort_words import rise_range
from auvdiag_cli.engine.ingest import ingest
from auvdiag_cli.jobs.effort import effort_log
from auvdiag_cli.jobs.relate import relation_log
from auvdiag_cli.vehicle.profile import Profile, load_profile
from models.command_relations import RelationLog
from models.effort import GroupFit
from models.effort_model import EffortModel, GroupSetup, learn_effort
from models.effort_thresholds import smallest_rise

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
NORMAL_MISSIONS = ("paper-normal", "mission-ccw", "mission-large-cw", "mission-sprint-ccw",
                   "mission-fast-cw")
FRACTIONS = (0.5, 0.6, 0.7, 0.8, 0.9)
CUT_MOTOR = "motor_3"      # the CrazyPAD E8 cuts are on M3


def _learn(profile: Profile, logs: list[RelationLog]) -> EffortModel:
    model, _ = learn_effort(profile.effort_groups, [effort_log(g, profile) for g in logs],
                            profile.dt_s)
    if model is None:
        raise SystemExit("no steady effort in the normal logs")
    return model


def _judge(model: EffortModel, profile: Profile, log: RelationLog) -> EffortCheck:
    # Only the verdict and the shares are tabled here, so the log's step index is its clock.
    return check_effort(model, profile, log.commands, log.usable,
                        profile.dt_s * np.arange(len(log.commands)))


def _percent(part: int, whole: int) -> str:
    return f"{part}/{whole} ({100 * part / whole:.0f} %)" if whole else "-"


def crazypad(root: Path) -> list[str]:
    profile = load_profile(Path("crazyflie"))
    with (root / "labels.csv").open() as stream:
        labels = list(csv.DictReader(stream))
    logs = {row["file"]: relation_log(ingest(root / row["file"], profile), profile)
            for row in labels}
    normal = [row["file"] for row in labels if row["kind"] == "normal"]
    model = _learn(profile, [logs[f] for f in normal])
    fit = next(f for f in model.fits if f is not None)
    lines = [f"**CrazyPAD E8** ({root}; {len(normal)} normal flights, {len(labels)} in all, "
             f"profile `crazyflie`): normal shares "
             + ", ".join(f"{m} {s:.3f} ± {d:.3f}" for m, s, d in zip(
                 fit.group.members, fit.means.mean(axis=0), fit.spread, strict=True))
             + f" ({'conditioned on the level' if fit.conditioned else 'pooled'}, "
             f"{fit.window_s:.1f} s windows); driven harder past z "
             f"{model.thresholds.whole_log(fit) if model.thresholds else float('nan'):.2f} "
             f"for a budget of {model.false_alarm_rate:.0%} of normal flights.", ""]
    alarms = 0
    worst = 0.0
    normal_departure = -np.inf      # motor 3's largest, each normal flight judged by the others
    for f in normal:
        own = _learn(profile, [logs[g] for g in normal if g != f])
        check = _judge(own, profile, logs[f])
        alarms += bool(check.suspects)
        worst = max(worst, max((a.ratio or 0.0) for a in check.actuators))
        normal_departure = max(normal_departure, _departure(check, CUT_MOTOR))
    lines.append(f"Normal flights, each judged by the other {len(normal) - 1}: "
                 f"{alarms} false alarm(s) of {len(normal)} (largest z at {worst:.0%} of its "
                 "threshold).")
    lines += ["", "| defect | motors | flights | found | motor(s) named (count) |",
              "|---|---|---|---|---|"]
    by_class: dict[tuple[str, str, str], list[EffortCheck]] = defaultdict(list)
    for row in labels:
        if row["kind"] == "normal":
            continue
        key = (row["kind"], row["cut_mm"] or "", row["motors"])
        by_class[key].append(_judge(model, profile, logs[row["file"]]))
    cut_found = cut_total = cut_named = separable = 0
    for (kind, cut, motors), checks in sorted(by_class.items(), key=lambda i: (
            i[0][0], float(i[0][1] or 0), i[0][2])):
        found = [c for c in checks if c.suspects]
        named: dict[str, int] = defaultdict(int)
        for c in found:
            named[" and ".join(c.named)] += 1
        what = f"{kind} {cut} mm" if cut else kind
        lines.append(f"| {what} | {motors} | {len(checks)} | {_percent(len(found), len(checks))}"
                     f" | {', '.join(f'{k} ({v})' for k, v in sorted(named.items())) or '-'} |")
        if kind == "cut" and float(cut) >= 2.0:
            cut_total += len(checks)
            cut_found += len(found)
            cut_named += sum(c.named == (CUT_MOTOR,) for c in found)
            separable += sum(_departure(c, CUT_MOTOR) > normal_departure for c in checks)
    lines += ["", f"Cut of 2 mm or more: found in {_percent(cut_found, cut_total)} of the "
              f"flights, motor 3 alone named in {_percent(cut_named, cut_found)} of those "
              f"found. Separable at all: in {_percent(separable, cut_total)} motor 3 carries "
              f"more of the effort than on any normal flight (+{normal_departure:.1%} at most, "
              "each judged by the others): what any threshold on its share could find without "
              "a false alarm."]
    return lines


def _departure(check: EffortCheck, motor: str) -> float:
    """The motor's share less its normal share, over the normal share (NaN: not judged)."""
    departure = next(a.departure for a in check.actuators if a.name == motor)
    return float("nan") if departure is None else departure


def crazypad_few(root: Path) -> list[str]:
    """Trained on every choice of 3 and of 4 of the normal flights: false alarms on the
    normal flights left out, and the cut flights found by cut size; each member's spread
    drawn towards the group's (now) and each member's own (the yardstick), in one run."""
    import models.effort

    profile = load_profile(Path("crazyflie"))
    with (root / "labels.csv").open() as stream:
        labels = list(csv.DictReader(stream))
    logs = {row["file"]: relation_log(ingest(root / row["file"], profile), profile)
            for row in labels if row["kind"] in ("normal", "cut")}
    normal = [row["file"] for row in labels if row["kind"] == "normal"]
    cuts = sorted({float(row["cut_mm"]) for row in labels if row["kind"] == "cut"})
    by_cut = {c: [row["file"] for row in labels if row["kind"] == "cut"
                  and float(row["cut_mm"]) == c] for c in cuts}
    pooled = models.effort.between_spread
    lines = ["", "**CrazyPAD E8 with few normal flights**: trained on every choice of k of the "
             f"{len(normal)} normal flights; false alarms on the normal flights left out; the "
             "cut flights found (motor 3 alone named in every one found unless said), by cut; "
             "choices cautioned: those whose flights differ no more than their own noise "
             "makes them (`train` says so), and in brackets the false alarms with them; the "
             "smallest rise of one motor's share that the choice's model judges over a flight "
             "(`train` says it), median over the choices and their range; flights not ruled "
             "out: no alarm, but a motor past the threshold a 5 % budget would set, its shares "
             "matching its weakness (the verdict undetermined; of the cut ones, those with "
             "motor 3 the candidate):",
             "", "| spreads | k | false alarms | normal not ruled out | choices cautioned | "
             "smallest rise judged | " + " | ".join(f"cut {c:g} mm" for c in cuts)
             + " | cut ≥ 2 mm | cut ≥ 2 mm not ruled out |", "|---" * (len(cuts) + 8) + "|"]
    # Motor 3's largest statistic over its threshold, per cut flight of 2 mm or more and
    # choice of 4 normal flights, as shipped: which flights the misses are.
    ratios: dict[str, list[float]] = defaultdict(list)
    for label, spread in (("drawn towards the group's", pooled),
                          ("each member's own", functools.partial(pooled, pool=False))):
        # The yardstick swaps the spread estimate itself, everything else as shipped.
        models.effort.between_spread = spread   # type: ignore[assignment]
        try:
            for k in (3, 4):
                lines.append(_few_row(profile, logs, normal, by_cut, k, label,
                                      ratios if spread is pooled and k == 4 else None))
        finally:
            models.effort.between_spread = pooled
    return [*lines, "", _misses_by_folder(ratios)]


def _misses_by_folder(ratios: dict[str, list[float]]) -> str:
    """The cut folders (2 mm or more) that some choice of 4 normal flights misses, with
    motor 3's statistic over its threshold there: median over the choices and flights, and
    the range."""
    folders: dict[str, list[float]] = defaultdict(list)
    for file, values in ratios.items():
        folders[Path(file).parent.name] += values
    missed = [f"`{name}` {np.median(v):.2f} ({min(v):.2f}-{max(v):.2f})"
              for name, v in sorted(folders.items()) if min(v) <= 1.0]
    return ("With 4 normal flights as shipped, the cut folders of 2 mm or more that some "
            "choice misses, and motor 3's largest statistic over its threshold there (median "
            "over the choices and the folder's flights, and the range): "
            + ("; ".join(missed) or "none") + ".")


def _few_row(profile: Profile, logs: dict[str, RelationLog], normal: list[str],
             by_cut: dict[float, list[str]], k: int, label: str,
             ratios: dict[str, list[float]] | None = None) -> str:
    """A table row for choices of ``k``; ``ratios``: filled with motor 3's statistic over
    its threshold per cut flight of 2 mm or more, one per choice."""
    alarms = judged = unruled = unruled_cut = 0
    found: dict[float, int] = defaultdict(int)
    tried: dict[float, int] = defaultdict(int)
    wrong = 0
    # Choices whose flights differ no more than their own noise (the caution `train` gives),
    # and the false alarms with them.
    alike = alike_alarms = 0
    folds = 0
    rises = []      # per choice, the smallest rise of one motor's share its model judges
    for chosen in itertools.combinations(normal, k):
        folds += 1
        model = _learn(profile, [logs[f] for f in chosen])
        rises += [float(np.mean(smallest_rise(f, model.thresholds))) for f in model.fits
                  if f is not None and model.thresholds is not None]
        cautioned = any(f is not None and f.alike for f in model.fits)
        alike += cautioned
        for f in normal:
            if f not in chosen:
                judged += 1
                check = _judge(model, profile, logs[f])
                alarm = bool(check.suspects)
                alarms += alarm
                unruled += check.not_ruled_out is not None
                alike_alarms += alarm and cautioned
        for cut, files in by_cut.items():
            for f in files:
                check = _judge(model, profile, logs[f])
                tried[cut] += 1
                found[cut] += bool(check.suspects)
                wrong += cut >= 2.0 and bool(check.suspects) and check.named != (CUT_MOTOR,)
                unruled_cut += cut >= 2.0 and check.not_ruled_out == CUT_MOTOR
                if ratios is not None and cut >= 2.0:
                    ratios[f].append(next(a.ratio or 0.0 for a in check.actuators
                                          if a.name == CUT_MOTOR))
    big = [c for c in by_cut if c >= 2.0]
    cells = [_percent(found[c], tried[c]) for c in by_cut]
    return (f"| {label} | {k} | {_percent(alarms, judged)} | {_percent(unruled, judged)} | "
            f"{alike}/{folds} ({alike_alarms}) | "
            f"{np.median(rises):.0%} ({min(rises):.0%}-{max(rises):.0%}) | "
            + " | ".join(cells) + " | "
            f"{_percent(sum(found[c] for c in big), sum(tried[c] for c in big))}"
            + (f" ({wrong} named otherwise)" if wrong else "")
            + f" | {_percent(unruled_cut, sum(tried[c] for c in big))} |")


def _simulated(profile: Profile, scenario_name: str, seed: int, work: Path,
               fraction: float | None = None, onset_s: float | None = None) -> RelationLog:
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import get_scenario
    from auvdiag_cli.simulator.writers import write_log

    scenario = get_scenario(scenario_name, profile, onset_s, severity=fraction)
    path = work / f"{scenario_name}-{seed}-{fraction}-{onset_s}.tlog"
    if not path.exists():       # the same mission asked for again: simulated once
        write_log(simulate(scenario, profile, seed), profile, path, "tlog")
    return relation_log(ingest(path, profile), profile)


def _rise(model: EffortModel, setup: GroupSetup, fit: GroupFit | None,
          change: GroupFit | None) -> str:
    """The smallest rise of one member's share the group's whole-log test judges, and the
    later-start test where it weakens halfway through a mission (no one figure where that
    is judged along the mixer's signatures over the change bin)."""
    if fit is None or model.thresholds is None:
        return ""
    whole = f"; judged from a rise of {rise_range(list(smallest_rise(fit, model.thresholds)))}"
    if change is not None and setup.change_bin is not None:
        return whole + ", within a mission along the mixer's signatures under way"
    later = smallest_later_rise(setup, fit, model.thresholds, model.dt_s)
    return whole + f", from halfway {rise_range(list(later))}"


def _conditions(two_way: bool, fit: GroupFit | None) -> str:
    if fit is None or not fit.conditioned:
        return "pooled"
    return "by thrust direction" if two_way else "by level"


FAULT_FROM_S = 60.0     # the weak scenarios' fault begins here
NEVER_S = 1e6           # a fault from here: the mission flown without it
# A weakness that begins late: this much thrust kept from this long before the actuator last
# works at its mean thrust; and one that stops a few seconds before that, as in a crash
# (a crash ends a log with its parts at work, not idling at a mission's end).
LATE_FRACTION, LATE_BEFORE_LAST_WORK_S = 0.7, (10.0, 20.0)
STOPPED_BEFORE_LAST_WORK_S = (1.5, 3.0, 5.0)
# Per actuator named alone: its onset and detection after the fault began, and the error
# it stated of the onset (None: it found the whole log departing).
Timing = tuple[float, float, float | None]


def simulated(profile_name: str, title: str, training_logs: int) -> list[str]:
    profile = load_profile(Path(profile_name))
    times: list[Timing] = []
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        training = [_simulated(profile, name, seed, work)
                    for seed in (1, 2, 3) for name in NORMAL_MISSIONS][:training_logs]
        model = _learn(profile, training)
        normal = [_judge(model, profile, _simulated(profile, name, seed, work))
                  for seed in (101, 102) for name in NORMAL_MISSIONS]
        components = [c.component for c in profile.commands]
        rows = []
        for fraction in FRACTIONS:
            cells = []
            timed = len(times)
            for component in components:
                check = _judge(model, profile, _simulated(
                    profile, _weak(component), 201, work,
                    fraction))
                named = set(check.named)
                mark = "?" if check.not_ruled_out == component else "-"
                if check.suspects:
                    mark = ("named" if named == {component} else "other"
                            if component not in named else "in a pair" if len(named) == 2
                            else f"among {len(named)}")
                if (mark == "named" and check.onset_s is not None
                        and check.alarm_s is not None):
                    times.append((check.onset_s - FAULT_FROM_S, check.alarm_s - FAULT_FROM_S,
                                  check.onset_error_s))
                cells.append(mark)
            rows.append(f"| {fraction:.0%} | " + " | ".join(cells)
                        + f" | {_row_timing(times[timed:])} |")
        late = [*_late(profile, model, components, work, LATE_FRACTION, LATE_BEFORE_LAST_WORK_S),
                *_late(profile, model, components, work, 0.0, STOPPED_BEFORE_LAST_WORK_S),
                _seeds(profile, model, components, work)]
    alarms = sum(bool(c.suspects) for c in normal)
    unruled = sum(c.not_ruled_out is not None for c in normal)
    changes = model.change_fits or (None,) * len(model.setups)
    groups = ", ".join(f"{setup.group.name} ({_conditions(setup.two_way, fit)}"
                       f"{_rise(model, setup, fit, change)})"
                       for setup, fit, change in zip(model.setups, model.fits, changes,
                                                     strict=True))
    return ["", f"**Simulated {title}** (`{profile_name}`, {len(training)} normal missions to "
            f"learn from; groups {groups}): false alarms on {len(normal)} normal missions of "
            f"other seeds: {alarms} (not ruled out: {unruled}). One actuator weakened from "
            "60 s (- not found; ? not found but not ruled out, it the candidate; named; in a "
            "pair, among n: named with others it cannot be told from; a group's rise: the "
            "smallest rise of one member's share its whole-log test judges over a mission, "
            "and its test against the mission's own beginning where it weakens halfway; "
            "onset and detection after 60 s, median over those named alone):", "",
            "| thrust kept | " + " | ".join(components) + " | onset / detected (s) |",
            "|---" * (len(components) + 2) + "|", *rows, "", _timing(times), "", *late]


def _weak(component: str) -> str:
    """The scenario of ``component`` weakened."""
    return f"mission-{component.replace('_', '-')}-weak"


def _late(profile: Profile, model: EffortModel, components: list[str], work: Path,
          fraction: float, befores_s: tuple[float, ...]) -> list[str]:
    """Each actuator keeping ``fraction`` of its thrust from each of ``befores_s``
    before it last works at its mean thrust (`SimulatedDive.last_works_s`, on the mission
    flown without the fault): named alone, the true onset within the error stated, the
    detection after it (never before)."""
    from auvdiag_cli.simulator.run import simulate
    from auvdiag_cli.simulator.scenarios import get_scenario

    lines = []
    fault_free = {c: simulate(get_scenario(_weak(c), profile, NEVER_S), profile, 201)
                  for c in components}
    for before_s in befores_s:
        named = held = 0
        delays, errors = [], []
        for actuator, component in enumerate(components):
            name = _weak(component)
            onset_s = round(fault_free[component].last_works_s(actuator, before_s), 1)
            check = _judge(model, profile, _simulated(profile, name, 201, work, fraction,
                                                      onset_s))
            if set(check.named) != {component} or check.alarm_s is None or (
                    check.alarm_s < onset_s):
                continue
            named += 1
            delays.append(check.alarm_s - onset_s)
            if check.onset_s is not None and check.onset_error_s is not None:
                errors.append(check.onset_error_s)
                held += abs(check.onset_s - onset_s) <= check.onset_error_s
        timing = (f"; the true onset within the error stated in {held} of {named} (stated "
                  f"error median {np.median(errors):.1f} s), detected {np.median(delays):.1f} s "
                  f"after it (median; worst {max(delays):.1f} s)" if delays and errors else "")
        what = (f"Stopped {before_s:g} s before it last works at its mean thrust (as in "
                "a crash)" if fraction == 0 else
                f"Weakened to {fraction:.0%} {before_s:g} s before it last works at its mean "
                "thrust")
        lines.append(f"- {what}: named alone, seen after it began, in "
                     f"{named} of {len(components)}{timing}.")
    return lines


SEEDS = tuple(range(301, 311))    # ten noise seeds of each weak mission


def _seeds(profile: Profile, model: EffortModel, components: list[str], work: Path) -> str:
    """Each actuator weakened to LATE_FRACTION from FAULT_FROM_S on missions of ten noise
    seeds: how many of them name it alone, and when."""
    named: dict[str, int] = {}
    paired: dict[str, int] = {}
    wrong = unruled = 0
    delays = []
    for component in components:
        named[component] = paired[component] = 0
        for seed in SEEDS:
            check = _judge(model, profile, _simulated(
                profile, _weak(component), seed, work,
                LATE_FRACTION))
            paired[component] += len(check.named) == 2 and component in check.named
            wrong += bool(check.named) and component not in check.named
            unruled += check.not_ruled_out == component
            if check.named == (component,):
                named[component] += 1
                if check.alarm_s is not None:
                    delays.append(check.alarm_s - FAULT_FROM_S)
    timing = (f"; detected {np.median(delays):.1f} s after the fault began (median; worst "
              f"{max(delays):.1f} s)" if delays else "")
    return (f"- Weakened to {LATE_FRACTION:.0%} from {FAULT_FROM_S:.0f} s on missions of "
            f"{len(SEEDS)} other noise seeds: named alone (in a pair) in "
            + ", ".join(f"{n} ({paired[c]}) of {len(SEEDS)} ({c})" for c, n in named.items())
            + f"; another named in its place in {wrong}; not found but not ruled out, it the "
            f"candidate, in {unruled}" + timing + ".")


def _row_timing(times: list[Timing]) -> str:
    """One thrust's onset and detection, median over the actuators named alone."""
    if not times:
        return "–"
    onset, detected = np.median(np.array([t[:2] for t in times]), axis=0)
    return f"{onset:+.1f} / {detected:.1f}"


def _timing(times: list[Timing]) -> str:
    if not times:
        return "No actuator named alone: no onset or detection to time."
    onset = np.array([t[0] for t in times])
    detected = np.array([t[1] for t in times])
    within = sum(error is not None and abs(start) <= error for start, _, error in times)
    return (f"Of the {len(times)} named alone, after the fault began at {FAULT_FROM_S:.0f} s: "
            f"onset estimated {np.median(onset):+.1f} s (median; {onset.min():+.1f} to "
            f"{onset.max():+.1f}), within the error it states in {within} of {len(times)}; "
            f"detected {np.median(detected):.1f} s after it (median; worst "
            f"{detected.max():.1f} s).")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    args = parser.parse_args()
    lines = [f"Measured {date.today()} on {platform.machine()} ({os.cpu_count()} cores), "
             f"Python {platform.python_version()}.", ""]
    root = args.data / "crazypad"
    if (root / "labels.csv").is_file():
        lines += crazypad(root)
        lines += crazypad_few(root)
    else:
        lines.append(f"CrazyPAD: not found at {root} (skipped).")
    for training_logs in (15, 3):
        lines += simulated("bluerov2", "BlueROV2", training_logs)
        lines += simulated("arducopter_quad", "quadrotor", training_logs)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
