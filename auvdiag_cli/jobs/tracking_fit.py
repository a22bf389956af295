"""model.json's `tracking`: each loop of the profile's `[[tracking]]` fitted on the normal
logs `train` learns from (`models.tracking`), its lag the one at which the change test finds
their gains steadiest against their own beginnings: what sets its thresholds."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.engine.change_check import REFERENCE_MIN_S, SUM, way_statistics
from auvdiag_cli.vehicle.profile import Profile
from models.skill import ScoringLog
from models.tracking import fit_tracking


def tracking_entry(profile: Profile, logs: Sequence[ScoringLog]) -> list[dict[str, object]]:
    """The fitted loops as model.json keeps them (none where the profile declares none)."""
    def unsteadiness(gains: Sequence[np.ndarray]) -> float:
        """The change test's sum below, at its largest in each log, averaged over them."""
        peaks = [way_statistics(gain[:, None], profile.window_samples,
                                round(REFERENCE_MIN_S / profile.dt_s), below_only=[0])[SUM][:, 1]
                 for gain in gains]
        return float(np.mean([np.nanmax(p) if np.isfinite(p).any() else 0.0 for p in peaks]))

    return [fit.to_json() for fit in fit_tracking(
        profile.tracking, [(log.commands, log.sensors) for log in logs], profile.drive_names,
        profile.sensor_names, profile.dt_s, unsteadiness)]
