"""Beyond the paper's assumption 3 (a component is normal or totally defective): a thruster
that lost part of its power. Its signature can look like a sensor fault to the pattern
table (at 50 % the yaw residual grows first), so when the table names a sensor the log is
also replayed under "thruster k gives only a fraction of its thrust from the onset on". If
one such replay explains every sensor (no g reaches its threshold after the onset) while the
table's sensor hypothesis cannot, the weakened thruster is the better diagnosis. Fraction 0
is tried too: a thruster that dies in a turn can raise the yaw bit alone at first, which
the table reads as the yaw-rate sensor."""

from dataclasses import dataclass, replace

import numpy as np

from auvdiag_cli.matching import match
from auvdiag_cli.numeric import peak
from auvdiag_cli.profile import Profile
from auvdiag_cli.resample import AlignedFrame
from models.store import LoadedModel

THRUST_FRACTIONS = (0.0, 0.25, 0.5, 0.75)


@dataclass(frozen=True)
class WeakenedThruster:
    component: str
    thrust_fraction: float
    peak_g_ratio: float          # the largest g / threshold after the onset with it assumed


def explain_by_weak_thruster(model: LoadedModel, profile: Profile, frame: AlignedFrame,
                             thresholds: np.ndarray, onset_index: int,
                             restarts: list[int]) -> WeakenedThruster | None:
    """The best weakened-thruster hypothesis, or None when none explains the log."""
    full_scale = model.metadata.get("full_scale", profile.full_scales)
    window = int(model.metadata.get("window_samples", profile.window_samples))
    judged_from = min(len(frame.time_s) - 1, onset_index + window)
    best: WeakenedThruster | None = None
    for index, command in enumerate(profile.commands):
        for fraction in THRUST_FRACTIONS:
            commands = frame.commands.copy()
            # Thrust grows as command·|command|: a fraction of thrust is sqrt of the command.
            commands[onset_index:, index] *= np.sqrt(fraction)
            trial = match(model, replace(frame, commands=commands), full_scale, window,
                          restarts)
            ratio = peak(trial.g_percent[judged_from:] / thresholds[judged_from:])
            if best is None or ratio < best.peak_g_ratio:
                best = WeakenedThruster(command.component, fraction, round(ratio, 3))
    return best if best is not None and best.peak_g_ratio < 1.0 else None
