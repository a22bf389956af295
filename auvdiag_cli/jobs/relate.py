"""Learning how a vehicle's commands follow its motion (`models.command_relations`) from
normal logs: part of `auvdiag train`, and `auvdiag relate` for an existing model."""

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from auvdiag_cli.engine.ingest import IngestedLog, ingest
from auvdiag_cli.engine.segments import mission_steps, segments_of
from auvdiag_cli.engine.start_check import StartReading, learn_start_state, start_reading
from auvdiag_cli.jobs.holdout import HELD_OUT_FRACTION, split_holdout, split_point
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import UsageError
from models.command_relations import RelationLog, RelationsRefused, fit_relations

if TYPE_CHECKING:
    from auvdiag_cli.engine.command_check import CommandCheck
    from models.store import LoadedModel



def relation_log(log: IngestedLog, profile: Profile) -> RelationLog:
    """The log's steps a relation may speak for: operating, outside the DMS runs (a DMS is
    a fixed command history, not commands that follow the motion)."""
    frame = log.frame
    return RelationLog(log.signals.path.name, frame.commands, frame.sensors,
                       mission_steps(segments_of(log, profile), frame.time_s, frame.operating))


def _split_in_time(log: RelationLog) -> tuple[RelationLog, RelationLog]:
    usable = log.usable & np.isfinite(log.sensors).all(axis=1)
    cut = split_point(usable)
    return (RelationLog(log.name, log.commands[:cut], log.sensors[:cut], log.usable[:cut]),
            RelationLog(f"{log.name} (last {HELD_OUT_FRACTION:.0%})", log.commands[cut:],
                        log.sensors[cut:], log.usable[cut:]))


def learn_relations(training: Sequence[RelationLog], heldout: Sequence[RelationLog],
                    profile: Profile) -> dict[str, Any]:
    """The model.json entry: the relation, or why the logs could not teach one. One
    training log and no held-out one: its last 20 % (in time) sets the thresholds."""
    if not heldout and len(training) == 1:
        head, tail = _split_in_time(training[0])
        training, heldout = [head], [tail]
    scales = [profile.full_scales[name] for name in profile.sensor_names]
    try:
        relations = fit_relations(training, heldout, scales, profile.dt_s)
    except RelationsRefused as why:
        return {"refused": str(why)}
    return relations.to_json()


def relate_model(model: "LoadedModel", profile: Profile, logs: Sequence[Path],
                 holdout: Sequence[Path], progress: Callable[[str], None] = lambda _: None
                 ) -> tuple[dict[str, Any], dict[str, Any]]:
    """Learn, for an existing model, how the commands follow the motion and where normal
    logs recorded from rest start, and record both in the model's entries (not yet
    written); a refusal (the entry says why) keeps what the model had."""
    from auvdiag_cli.engine.diagnosis import check_model_fits

    for log in [*logs, *holdout]:
        check_model_fits(model, profile, log)
    training_paths, heldout_paths = split_holdout(logs, holdout)
    if not training_paths:
        raise UsageError("no logs left to learn from after holding out")
    progress(f"reading {len(training_paths)} logs to learn from and {len(heldout_paths)} "
             "held-out logs")
    training = [ingest(p, profile) for p in training_paths]
    heldout = [ingest(p, profile) for p in heldout_paths]
    relations = learn_relations([relation_log(log, profile) for log in training],
                                [relation_log(log, profile) for log in heldout], profile)
    def readings(logs: list[IngestedLog]) -> list[StartReading | None]:
        return [start_reading(log.frame.commands, log.frame.sensors, profile.dt_s)
                for log in logs]

    start = learn_start_state(readings(training), readings(heldout),
                              [profile.full_scales[n] for n in profile.sensor_names])
    model.update_entries(**{key: entry for key, entry in (
        ("command_relations", relations), ("start_state", start)) if "refused" not in entry})
    return relations, start


def widen_thresholds(model: "LoadedModel", checks: Sequence["CommandCheck | None"],
                     margin: float) -> dict[str, float]:
    """Raise, in the model's command relations, each actuator's allowed extra effort to ``margin``
    times the most these normal logs reached where that is more (never lower: the held-out
    logs set it): no calibration log may alarm. Returns the raised thresholds by command."""
    entry = model.entry("command_relations")
    if "thresholds" not in entry:
        return {}
    raised = {}
    names = model.command_names
    for check in checks:
        if check is None:
            continue
        for k, name in enumerate(names):
            threshold, ratio = entry["thresholds"][k], check.peak_ratio.get(name)
            if threshold is not None and ratio is not None and margin * ratio > 1.0:
                entry["thresholds"][k] = round(margin * ratio * threshold, 6)
                raised[name] = entry["thresholds"][k]
    model.update_entries(command_relations=entry)
    return raised
