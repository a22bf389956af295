"""A simulated quadrotor's four rotors as the effort check reads them: commands of rotors
hovering near half throttle, an effort model learnt from such logs, and one log judged."""

from pathlib import Path

import numpy as np

from auvdiag_cli.engine.effort_check import EffortCheck, check_effort
from auvdiag_cli.vehicle.profile import load_profile
from models.effort_model import EffortLog, EffortModel, learn_effort

PROFILE = load_profile(Path("arducopter_quad"))
STEPS = 1200                       # 120 s at 10 Hz
SHARES = np.array([1.03, 0.97, 1.02, 0.98])


def quad_commands(rng: np.random.Generator, trim: np.ndarray) -> np.ndarray:
    """Four rotors hovering near half throttle, each carrying its share times ``trim``."""
    level = 0.5 + 0.03 * np.sin(np.arange(STEPS) / 80.0)
    return level[:, None] * SHARES * trim * (1 + rng.normal(0, 0.06, (STEPS, 4)))


def quad_model(logs: list[np.ndarray]) -> EffortModel:
    model, _ = learn_effort(PROFILE.effort_groups, [
        EffortLog(f"normal-{i}", c, np.ones(STEPS, bool), PROFILE.command_names)
        for i, c in enumerate(logs)], PROFILE.dt_s)
    assert model is not None and model.fits[0] is not None
    return model


def quad_check(model: EffortModel, commands: np.ndarray) -> EffortCheck:
    return check_effort(model, PROFILE, commands, np.ones(STEPS, bool),
                        PROFILE.dt_s * np.arange(STEPS))
