"""The two forms of the commands-against-the-motion relation, and which one a vehicle's
normal logs keep: each actuator's commands learned from the motion
(`models.command_relations`), or the motion learned from each actuator's thrust
(`models.thrust_relations`). Both are fitted; the one that judges the smaller loss of thrust
(the median over the actuators, at the thresholds held-out normal logs set) is kept."""

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from models.command_relations import CommandRelations, fit_relations
from models.relation_windows import RelationLog, RelationsRefused
from models.skill import MIN_SKILL
from models.thrust_relations import ThrustRelations, fit_thrust_relations

Relations = CommandRelations | ThrustRelations


def relations_from_json(entry: dict[str, Any]) -> Relations:
    """Raises ValueError where the entry does not fit; an entry without a form (a model
    trained before the thrust form) is the commands' form."""
    if entry.get("form", "commands") == "thrust":
        return ThrustRelations.from_json(entry)
    return CommandRelations.from_json(entry)


def smallest_loss(relations: Relations) -> np.ndarray:
    """Per actuator, the share of its thrust it must lose before the main window's threshold
    is reached (1: never judged; the commands' form's extra command converted, `as_loss`)."""
    allowed = relations.as_loss(relations.thresholds)
    judged = np.isfinite(allowed) & (np.nan_to_num(relations.skill, nan=-1.0) >= MIN_SKILL)
    return np.where(judged, np.minimum(allowed, 1.0), 1.0)


def _median(relations: Relations) -> float:
    """Rounded: two forms both at the least loss judged (`least_loss`) tie exactly, where
    the commands' form's converted floor differs from the thrust form's in the last bits."""
    return round(float(np.median(smallest_loss(relations))), 9)


def learn_relations_forms(training: Sequence[RelationLog], heldout: Sequence[RelationLog],
                          sensor_scale: Sequence[float], dt_s: float) -> Relations:
    """Both forms, the one that judges the smaller loss kept (the commands' form on a tie),
    with why in its ``fitted_on.chosen``. Raises RelationsRefused where neither can be
    learnt (the message of the commands' form)."""
    forms: list[Relations] = []
    refused: RelationsRefused | None = None
    for fit in (lambda: fit_relations(training, heldout, sensor_scale, dt_s),
                lambda: fit_thrust_relations([*training, *heldout], sensor_scale, dt_s)):
        try:
            forms.append(fit())
        except RelationsRefused as cannot:
            refused = refused or cannot
    if not forms:
        raise refused or RelationsRefused("no logs to learn how the commands follow the motion")
    if len(forms) == 1:
        return forms[0]
    commands, thrust = forms
    kept, other = (thrust, commands) if _median(thrust) < _median(commands) else (
        commands, thrust)
    why = (f"{_NAMES[kept.measure]} judges a loss of thrust from {_median(kept):.0%} (median "
           f"over the actuators), {_NAMES[other.measure]} from {_median(other):.0%}"
           if _median(kept) < 1.0 else f"neither form judges most actuators; "
           f"{_NAMES[kept.measure]} kept")
    return replace(kept, fitted_on=replace(kept.fitted_on, chosen=why))


_NAMES = {CommandRelations.measure: "the commands learnt from the motion",
          ThrustRelations.measure: "the motion learnt from each actuator's thrust"}
