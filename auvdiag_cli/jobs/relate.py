"""Learning how a vehicle's commands follow its motion (`models.command_relations`) from
normal logs: part of `auvdiag train`, and `auvdiag relate` for an existing model."""

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from auvdiag_cli.engine.ingest import IngestedLog, ingest
from auvdiag_cli.engine.segments import mission_steps, segments_of
from auvdiag_cli.engine.start_check import StartReading, learn_start_state, start_reading
from auvdiag_cli.jobs.holdout import HELD_OUT_FRACTION, split_holdout, split_point
from auvdiag_cli.vehicle.actuators import SET_POINT
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import UsageError
from models.card import Refused, StartReference
from models.relation_forms import Relations, learn_relations_forms
from models.relation_windows import RelationLog, RelationsRefused

if TYPE_CHECKING:
    from auvdiag_cli.engine.command_check import CommandCheck
    from models.store import LoadedModel



def relation_log(log: IngestedLog, profile: Profile) -> RelationLog:
    """The log's steps a relation may speak for: operating, outside the DMS runs (a DMS is
    a fixed command history, not commands that follow the motion)."""
    frame = log.frame
    return RelationLog(log.signals.path.name, frame.commands, frame.sensors,
                       mission_steps(segments_of(log, profile), frame.time_s, frame.operating),
                       frame.efforts if frame.output_names else None)


def _split_in_time(log: RelationLog) -> tuple[RelationLog, RelationLog]:
    usable = log.usable & np.isfinite(log.sensors).all(axis=1)
    cut = split_point(usable)
    return (RelationLog(log.name, log.commands[:cut], log.sensors[:cut], log.usable[:cut]),
            RelationLog(f"{log.name} (last {HELD_OUT_FRACTION:.0%})", log.commands[cut:],
                        log.sensors[cut:], log.usable[cut:]))


def learn_relations(training: Sequence[RelationLog], heldout: Sequence[RelationLog],
                    profile: Profile) -> Relations | Refused:
    """The relation, or why the logs could not teach one. One
    training log and no held-out one: its last 20 % (in time) sets the thresholds."""
    if all(command.kind == SET_POINT for command in profile.commands):
        return Refused("the commands are the controller's set points, not actuators: no "
                       "actuator's effort to judge against the motion")
    if not heldout and len(training) == 1:
        head, tail = _split_in_time(training[0])
        training, heldout = [head], [tail]
    scales = [profile.full_scales[name] for name in profile.sensor_names]
    try:
        relations = learn_relations_forms(training, heldout, scales, profile.dt_s)
    except RelationsRefused as why:
        return Refused(str(why))
    return relations


def relate_model(model: "LoadedModel", profile: Profile, logs: Sequence[Path],
                 holdout: Sequence[Path], progress: Callable[[str], None] = lambda _: None
                 ) -> tuple[Relations | Refused, StartReference]:
    """Learn, for an existing model, how the commands follow the motion and where normal
    logs recorded from rest start, and record both in the model's entries (not yet
    written); a refusal (which says why) keeps what the model had."""
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
    learned: dict[str, Relations | StartReference] = (
        {} if isinstance(relations, Refused) else {"command_relations": relations})
    if start.refused is None:
        learned["start_state"] = start
    model.update_entries(**learned)
    return relations, start


def widen_thresholds(model: "LoadedModel", checks: Sequence["CommandCheck | None"],
                     margin: float) -> dict[str, float]:
    """Raise, in the model's command relations, each actuator's allowed extra effort (in
    every window) to ``margin`` times the most these normal logs reached where that is more
    (never lower: the held-out logs set it): no calibration log may alarm. Returns the
    raised thresholds by command ("NAME (10 s window)" for a shorter window's)."""
    relations = model.relations
    if relations is None:
        return {}
    windows = [w.thresholds.copy() for w in relations.windows]
    raised = {}
    for check in checks:
        for w, peaks in enumerate(() if check is None else check.peak_by_window):
            thresholds = windows[w]
            for k, name in enumerate(model.command_names):
                ratio = peaks.get(name)
                if not np.isnan(thresholds[k]) and ratio is not None and margin * ratio > 1.0:
                    thresholds[k] = round(margin * ratio * thresholds[k], 6)
                    label = relations.window_label(w)
                    raised[name if label is None else f"{name} ({label})"] = float(
                        thresholds[k])
    model.update_entries(command_relations=relations.with_window_thresholds(windows))
    return raised
