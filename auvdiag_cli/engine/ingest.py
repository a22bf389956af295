"""From a log path to signals on the model grid, through the right adapter."""

from dataclasses import dataclass
from pathlib import Path

from adapters import Signals, read_log
from auvdiag_cli.engine.autopilot_words import AutopilotSaid, said_while_operating
from auvdiag_cli.engine.flat_signals import (
    ABSENT,
    flat_input_notes,
    flat_sensor_notes,
    flat_sensors,
)
from auvdiag_cli.engine.outliers import remove_spikes
from auvdiag_cli.engine.resample import AlignedFrame, NeverOperates, resample
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import LogError, LogNotOperating


@dataclass
class IngestedLog:
    signals: Signals
    frame: AlignedFrame

    @property
    def autopilot_said(self) -> AutopilotSaid | None:
        """What the vehicle's own software said while it operated."""
        return said_while_operating(self.signals.autopilot_messages, self.signals.start_ns,
                                    self.frame.time_s, self.frame.operating)


# A stretch of a log on its own clock, in ns: (start, end), None for open at that end.
Part = tuple[int | None, int | None]
WHOLE: Part = (None, None)


def ingest(path: Path, profile: Profile, max_gap_s: float = 1.0, part: Part = WHOLE
           ) -> IngestedLog:
    """Read ``path`` with the profile's mapping and resample it to the profile's Δt; with
    ``part``, only that stretch of it (the healthy part of a log that failed later)."""
    signals = read_log(path, profile.sources)
    if part != WHOLE:
        whole = signals
        signals = signals.cropped(*part)
        empty = [name for name in (*profile.drive_names, *profile.sensor_names)
                 if name in whole.series and not len(signals.series[name])]
        if empty:
            raise LogError(path, f"its healthy part ({_seconds(part[0], 'its start')} to "
                                 f"{_seconds(part[1], 'its end')}) holds no sample of "
                                 f"{', '.join(empty)}; the log spans "
                                 f"{_seconds(whole.start_ns)} to {_seconds(whole.end_ns)} on "
                                 "its own clock")
    try:
        frame = resample(signals, profile.command_names, profile.sensor_names, profile.dt_s,
                         max_gap_s, profile.idle_after_s, profile.input_names,
                         profile.output_names)
    except NeverOperates as error:
        raise LogNotOperating(path, str(error)) from None
    except ValueError as error:
        raise LogError(path, str(error)) from None
    frame.flat = flat_sensors(frame.sensors, frame.sensor_names, profile.dt_s)
    frame.notes += flat_sensor_notes(frame.flat)
    if frame.input_names:
        frame.flat_inputs = flat_sensors(frame.inputs, frame.input_names, profile.dt_s) | {
            name: ABSENT for name in frame.input_names if name not in signals.series}
        frame.notes += flat_input_notes(frame.flat_inputs)
    frame.notes += [f"{name} {ABSENT}: an actuator output only the effort check reads"
                    for name in frame.output_names if name not in signals.series]
    frame.notes += remove_spikes(frame.sensors, frame.time_s, frame.sensor_names,
                                 profile.full_scales)
    return IngestedLog(signals, frame)


def _seconds(ns: int | None, open_end: str = "") -> str:
    return open_end if ns is None else f"{ns / 1e9:.3f} s"
