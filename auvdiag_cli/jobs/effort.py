"""Learning each actuator's normal share of the effort (`models.effort`) from normal logs:
part of `auvdiag train`, refitted by `auvdiag calibrate` with more normal logs."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.vehicle.actuators import SET_POINT
from auvdiag_cli.vehicle.profile import Profile
from models.card import Refused
from models.command_relations import RelationLog
from models.effort import DEFAULT_FALSE_ALARM_RATE
from models.effort_model import EffortLog, EffortModel, learn_effort

NO_GROUPS = ("not judged (the profile declares no actuators that act alike: add [[effort]] "
             "groups)")
# A model driven by set points reads actuator outputs only where the profile lists them.
NO_OUTPUTS = ("not judged (the profile's commands are the controller's set points and it reads "
              "no actuator outputs: list them in [[outputs]] and group them in [[effort]])")


def effort_log(log: RelationLog, profile: Profile) -> EffortLog:
    """The steps an effort share may speak for are those a command relation may: operating,
    outside the DMS runs (fixed commands, not a controller's)."""
    efforts = log.commands if log.efforts is None else log.efforts
    return EffortLog(log.name, efforts, log.usable, profile.effort_names)


def learn_effort_model(logs: Sequence[RelationLog], profile: Profile,
                       false_alarm_rate: float = DEFAULT_FALSE_ALARM_RATE
                       ) -> tuple[EffortModel | Refused, list[str]]:
    """The effort model (or why there is none), and notes on logs left out."""
    if not profile.effort_groups:
        set_points_only = not profile.outputs and all(
            c.kind == SET_POINT for c in profile.commands)
        return Refused(NO_OUTPUTS if set_points_only else NO_GROUPS), []
    effort_logs = [effort_log(g, profile) for g in logs]
    model, notes = learn_effort(profile.effort_groups, effort_logs, profile.dt_s,
                                false_alarm_rate)
    if model is None:
        members = dict.fromkeys(m for group in profile.effort_groups for m in group.members)
        unheard = [name for name in members
                   if not any(np.isfinite(log.group_commands_of([name])).any()
                              for log in effort_logs)]
        return Refused(f"not judged (no log trained on holds {', '.join(unheard)})" if unheard
                       else "not judged (the actuators of its groups never work at a steady "
                            "level, min_level or more, in these logs)"), notes
    return model, notes


def refit_effort(model: EffortModel, logs: Sequence[RelationLog], profile: Profile,
                 false_alarm_rate: float | None) -> tuple[EffortModel, list[str]]:
    """``model`` with these normal logs added (those it already holds are not counted twice)
    and, when given, a new false-alarm budget."""
    return model.with_logs([effort_log(g, profile) for g in logs], false_alarm_rate)
