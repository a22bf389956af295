"""From a log path to signals on the model grid, through the right adapter."""

from dataclasses import dataclass
from pathlib import Path

from adapters import Signals, read_log
from auvdiag_cli.engine.outliers import remove_spikes
from auvdiag_cli.engine.resample import AlignedFrame, NeverOperates, resample
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import LogError, LogNotOperating


@dataclass
class IngestedLog:
    signals: Signals
    frame: AlignedFrame


def ingest(path: Path, profile: Profile, max_gap_s: float = 1.0) -> IngestedLog:
    """Read ``path`` with the profile's mapping and resample it to the profile's Δt."""
    signals = read_log(path, profile.sources)
    try:
        frame = resample(signals, profile.command_names, profile.sensor_names, profile.dt_s,
                         max_gap_s, profile.idle_after_s, profile.input_names)
    except NeverOperates as error:
        raise LogNotOperating(path, str(error)) from None
    except ValueError as error:
        raise LogError(path, str(error)) from None
    frame.notes += remove_spikes(frame.sensors, frame.time_s, frame.sensor_names,
                                 profile.full_scales)
    return IngestedLog(signals, frame)
