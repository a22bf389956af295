"""The g thresholds a newly trained model starts with: the profile's, raised where the logs
held out of its training show more (calibrate's margin rule on them, never below the
profile's).

A profile's thresholds are set for a model of its vehicle learnt from many logs; a model
learnt from a handful errs more, and judged by them it alarms on normal logs (the simulated
BlueROV2 trained on three missions: every one of ten normal missions of other seeds). The
held-out logs are the fair measure of its error: the replay was not fitted to them.
`calibrate` on more normal logs sets the thresholds anew."""

from collections.abc import Sequence
from pathlib import Path

from auvdiag_cli.engine.diagnosis import diagnose_ingested
from auvdiag_cli.engine.ingest import ingest
from auvdiag_cli.jobs.calibrate import DEFAULT_CALIBRATION, g_by_mode, margin_modes
from auvdiag_cli.jobs.healthy import HealthyParts
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

Thresholds = dict[str, dict[str, float]]


def heldout_thresholds(model: LoadedModel, profile: Profile, heldout: Sequence[Path],
                       healthy: HealthyParts) -> Thresholds:
    """Per mode and signal: the profile's threshold, or the margin times the largest g the
    ``heldout`` logs (the parts of them trained on, ``healthy``) reach where that is more;
    ``model`` as written, with the profile's thresholds."""
    thresholds = {mode: dict(values) for mode, values in profile.thresholds.items()}
    if not heldout:
        return thresholds
    per_log = [g_by_mode(diagnose_ingested(ingest(path, profile, part=healthy.of(path)),
                                           profile, model)) for path in heldout]
    for mode in margin_modes([path.name for path in heldout], per_log, profile,
                             DEFAULT_CALIBRATION.margin, True, model):
        thresholds[mode.mode] = mode.thresholds
    return thresholds


def raised(before: Thresholds, after: Thresholds) -> list[str]:
    """'mode signal from -> to' for each threshold ``after`` raised."""
    return [f"{mode} {name} {value:g} -> {after[mode][name]:g} %"
            for mode, values in before.items() for name, value in values.items()
            if after.get(mode, {}).get(name, value) > value]
