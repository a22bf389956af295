"""model.json's `tracking`: each loop of the profile's `[[tracking]]` fitted on the normal
logs `train` learns from (`models.tracking`), its lag the one at which the change test finds
their gains steadiest against their own beginnings: what sets its thresholds."""

from collections.abc import Callable, Sequence

import numpy as np

from auvdiag_cli.engine.change_check import REFERENCE_MIN_S
from auvdiag_cli.engine.change_statistics import SUM, way_statistics
from auvdiag_cli.vehicle.profile import Profile
from models.skill import ScoringLog
from models.tracking import fit_tracking


def tracking_entry(profile: Profile, logs: Sequence[ScoringLog],
                   progress: Callable[[str], None] = lambda _: None) -> list[dict[str, object]]:
    """The fitted loops as model.json keeps them (none where the profile declares none),
    each said in ``progress``."""
    def unsteadiness(gains: Sequence[np.ndarray]) -> float:
        """The change test's sum below, at its largest in each log, averaged over them."""
        peaks = [way_statistics(gain[:, None], profile.window_samples,
                                round(REFERENCE_MIN_S / profile.dt_s), below_only=[0])[SUM][:, 1]
                 for gain in gains]
        return float(np.mean([np.nanmax(p) if np.isfinite(p).any() else 0.0 for p in peaks]))

    fits = fit_tracking(profile.tracking, [(_read_by_loops(log, profile), log.sensors)
                                           for log in logs],
                        profile.drive_names + profile.output_names, profile.sensor_names,
                        profile.dt_s, unsteadiness)
    for fit in fits:
        # A loop on a drive answers what is asked of a part; one on a set point, its error.
        answered, article = ("demand", "a") if fit.drive else ("error", "an")
        asked = f"of {' or '.join(fit.drive)} asked" if fit.drive else "of error"
        progress(f"the loop {fit.name}: a gain of {fit.typical:.3g} (the rate per unit "
                 f"{asked} {fit.lag_steps * profile.dt_s:.1f} s before), judged over "
                 f"{fit.window_steps * profile.dt_s:.0f} s windows from {article} {answered} of "
                 f"{fit.floor:.3g} rms, {answered}s beyond {fit.limit:.3g} left out "
                 "(saturated)")
    missing = {spec.name for spec in profile.tracking} - {fit.name for fit in fits}
    if missing:
        progress(f"not fitted (the logs never move what they answer): {', '.join(sorted(missing))}")
    return [fit.to_json() for fit in fits]


def _read_by_loops(log: ScoringLog, profile: Profile) -> np.ndarray:
    """What a loop may answer (`drive_names`, then `output_names`): the log's drive, then
    its actuator outputs (NaN where it has none)."""
    outputs = log.outputs if log.outputs is not None else np.full(
        (len(log.commands), len(profile.output_names)), np.nan)
    return np.hstack([log.commands, outputs])
