"""The normal logs `train` learns from, read onto the model grid: split into training and
held-out logs, each measured input a log never fed held at its typical value."""

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from auvdiag_cli.engine.autopilot_words import trouble_in_normal_log
from auvdiag_cli.engine.flat_signals import held_at, typical_inputs
from auvdiag_cli.engine.ingest import WHOLE, Part, ingest
from auvdiag_cli.jobs.healthy import NO_HEALTHY_PARTS, HealthyParts, announce_healthy_parts
from auvdiag_cli.jobs.holdout import HELD_OUT_FRACTION, split_holdout, split_point
from auvdiag_cli.jobs.operating import read_operating
from auvdiag_cli.jobs.relate import relation_log
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import UsageError
from models.command_relations import RelationLog
from models.skill import ScoringLog


@dataclass(frozen=True)
class ReadLog:
    scoring: ScoringLog
    relation: RelationLog
    rates_hz: dict[str, float]          # the rate each signal was logged at (median)
    flat_inputs: dict[str, str]         # measured inputs it never fed (`flat_signals`)


def read_for_training(path: Path, profile: Profile, progress: Callable[[str], None],
                      part: Part = WHOLE) -> ReadLog:
    """The log (or its ``part``) on the model grid, for the network and for the command
    relations."""
    log = ingest(path, profile, part=part)
    frame = log.frame
    for note in frame.slow_commands:
        progress(f"warning: {path.name}: {note}")
    trouble = trouble_in_normal_log(path.name, log.autopilot_said)
    if trouble:
        progress(trouble)
    rates = {}
    for name, series in log.signals.series.items():
        steps = np.diff(series.times_ns)
        if (steps > 0).any():
            rates[name] = 1e9 / float(np.median(steps[steps > 0]))
    outputs = frame.outputs if frame.output_names else None
    return ReadLog(ScoringLog(path.name, frame.drive, frame.sensors, tuple(frame.restarts),
                              outputs),
                   relation_log(log, profile), rates, frame.flat_inputs)


def _held(log: ReadLog, profile: Profile, typical: Mapping[str, float],
          unlearnt: Sequence[str] = ()) -> ScoringLog:
    """The log's scoring data, each measured input it never fed, and each ``unlearnt`` one
    (no log the model was trained on fed it), held at ``typical``."""
    held = {**log.flat_inputs, **dict.fromkeys(unlearnt, "")}
    if not held:
        return log.scoring
    return replace(log.scoring, commands=held_at(log.scoring.commands, profile.input_names,
                                                 held, typical))


def with_inputs_held(read: Sequence[ReadLog], read_heldout: Sequence[ReadLog],
                     profile: Profile, progress: Callable[[str], None]
                     ) -> tuple[list[ScoringLog], list[ScoringLog]]:
    """The training and held-out logs, each measured input a log never fed held at its
    median over the logs that fed it (`flat_signals.held_at`), which ``progress`` says."""
    every = [*read, *read_heldout]
    typical = typical_inputs([r.scoring.commands for r in every], profile.input_names,
                             [r.flat_inputs for r in every])
    for name in profile.input_names:
        unfed = [r.scoring.name for r in every if name in r.flat_inputs]
        if unfed:
            held_as = (f"held at {typical[name]:g}, its median on the other logs"
                       if name in typical else "no log fed it: the model cannot learn how it "
                       "acts, and every diagnosis holds it at the one value it had")
            progress(f"{name}: not fed (one value throughout, or not in the log) in "
                     f"{len(unfed)} of {len(every)} logs "
                     f"({', '.join(unfed[:3])}{', ...' if len(unfed) > 3 else ''}): {held_as}")
    return ([_held(r, profile, typical) for r in read],
            [_held(r, profile, typical) for r in read_heldout])


def scoring_log(path: Path, profile: Profile, progress: Callable[[str], None],
                typical: Mapping[str, float], unlearnt: Sequence[str] = ()) -> ScoringLog:
    """A log to score a model on, each measured input it never fed, and each ``unlearnt``
    one, held at the model's ``typical`` value."""
    return _held(read_for_training(path, profile, progress), profile, typical, unlearnt)


def median_rates(per_log: Sequence[dict[str, float]], names: Sequence[str]
                  ) -> dict[str, float]:
    return {name: round(float(np.median(values)), 3) for name in names
            if (values := [rates[name] for rates in per_log if name in rates])}


def split_in_time(log: ScoringLog) -> tuple[ScoringLog, ScoringLog]:
    """The log up to where 1 - HELD_OUT_FRACTION of its usable (operating, complete) steps
    lie, and the rest."""
    cut = split_point(np.isfinite(log.sensors).all(axis=1), HELD_OUT_FRACTION)
    outputs = log.outputs
    head = ScoringLog(log.name, log.commands[:cut], log.sensors[:cut],
                      tuple(c for c in log.cuts if c < cut),
                      None if outputs is None else outputs[:cut])
    tail = ScoringLog(f"{log.name} (last {HELD_OUT_FRACTION:.0%})", log.commands[cut:],
                      log.sensors[cut:], tuple(c - cut for c in log.cuts if c > cut),
                      None if outputs is None else outputs[cut:])
    return head, tail


def read_and_split(logs: Sequence[Path], holdout: Sequence[Path], profile: Profile,
                    progress: Callable[[str], None], healthy: HealthyParts = NO_HEALTHY_PARTS
                    ) -> tuple[list[Path], list[Path], dict[Path, ReadLog]]:
    """Training and held-out logs among those in which the vehicle operates, each read
    (only its healthy part where ``healthy`` lists one)."""
    paths = list(dict.fromkeys([*logs, *holdout]))
    # How many are held out is known only once the logs are read (see `split_holdout`).
    progress(f"reading {len(paths)} log(s)"
             + (f", {len(holdout)} of them held out as asked" if holdout else ""))
    announce_healthy_parts(healthy, paths, progress)
    every = read_operating(paths, lambda path: read_for_training(
        path, profile, progress, healthy.of(path)), progress, "train on")
    training_paths, heldout_paths = split_holdout([p for p in logs if p in every],
                                                  [p for p in holdout if p in every])
    if not training_paths:
        raise UsageError("no training logs left after holding out")
    return training_paths, heldout_paths, every
