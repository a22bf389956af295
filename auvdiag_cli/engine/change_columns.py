"""What the change test judges on a log: one column per sensor (the error of the model's
predictor a moment ahead, or of its replay) and one per loop of the controller whose gain
the model keeps (`models.tracking`: the gain less its typical value); and, of the signals
the profile leaves to it, why it judges none it leaves out."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.engine.change_check import MIN_JUDGED_S, ChangeCheck
from auvdiag_cli.engine.judging import Judging, not_judged_signals, own_log_only
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.residuals import Matching
from models.ahead import MIN_AHEAD_SKILL
from models.store import LoadedModel


def loop_names(model: LoadedModel) -> list[str]:
    """The loops the model keeps: each judged below its typical gain only (a part that
    fails makes a loop slower; one that answers faster is no failure of its parts)."""
    return [loop.name for loop in model.card.tracking]


def change_names(model: LoadedModel) -> list[str]:
    """The columns of `change_residual`: the sensors, then the loops."""
    return [*model.card.sensor_names, *loop_names(model)]


def change_judged(model: LoadedModel, replay_judged: Sequence[str]) -> list[str]:
    """The signals the test judges: those the predictor a moment ahead predicts better than
    "no change" on held-out data, or, for a model without one, those the replay judges;
    then every loop the model keeps."""
    ahead = model.card.ahead
    loops = loop_names(model)
    if ahead is None:
        return [*replay_judged, *loops]
    return [*(name for name in model.card.sensor_names
              if ahead.skill.get(name, 0.0) >= MIN_AHEAD_SKILL), *loops]


def judged_by(change: ChangeCheck | None) -> frozenset[str]:
    """The signals the change test judges on a log: each with a threshold, and the members
    of its signatures (some judged nowhere else: `signature_only`); none where it is not
    judged."""
    if change is None or not change.judged:
        return frozenset()
    limited = {name for limits in change.thresholds.values() for name in limits}
    return frozenset(limited | {m for name in limited for m in change.members.get(name, ())})


def left_by_the_change_test(change: ChangeCheck | None, judging: Judging) -> dict[str, str]:
    """Why a signal the profile judges only against the log's own beginning is not judged
    at all, where the change test judges the log but not that signal (the replay's reason,
    "judged only against the log's own beginning", would say it is): its predictor a
    moment ahead barely beats "no change" there, or calibrate set it no threshold."""
    judged = judged_by(change)
    if not judged:
        return {}
    return {name: (f"not judged ({_why_not(judging.model, name)}; the profile judges it only "
                   "against the log's own beginning)")
            for name in own_log_only(judging.profile)
            if name not in judged and name not in judging.set_aside}


def _why_not(model: LoadedModel, name: str) -> str:
    if name in model.card.change_too_brief:
        return (f"calibrate's normal logs let the change test judge it for "
                f"{model.card.change_too_brief[name]:.1f} s in all, too little to set its "
                f"thresholds (needs {MIN_JUDGED_S:.0f} s)")
    ahead = model.card.ahead
    if ahead is None:       # the test judges the replay's error, where the model has skill
        return ("the model cannot predict it" if name in not_judged_signals(model)
                else "calibrate set it no threshold")
    skill = ahead.skill.get(name)
    if skill is not None and skill < MIN_AHEAD_SKILL:
        return (f"its predictor a moment ahead barely beats no change: skill {skill:.2f}, "
                f"judged from {MIN_AHEAD_SKILL:g}")
    return "calibrate set it no threshold"


def change_residual(model: LoadedModel, frame: AlignedFrame, matching: Matching,
                    cuts: Sequence[int] = ()) -> np.ndarray:
    """What the test judges (columns `change_names`): the error of the model's predictor a
    moment ahead (`models.ahead`, from the log's commands and measured inputs), or the
    replay's where the model has none (trained before it); then each loop's gain less its
    typical value (a loop reads the commands and the actuator outputs)."""
    ahead = model.card.ahead
    errors = matching.measured - matching.modelled if ahead is None else ahead.residual(
        frame.commands, matching.measured, frame.inputs if frame.input_names else None, cuts)
    card = model.card
    gains = [loop.gain(frame.efforts, matching.measured, [*card.command_names, *frame.output_names],
                       card.sensor_names, card.dt_s) for loop in card.tracking]
    return np.column_stack([errors, *gains]) if gains else errors
