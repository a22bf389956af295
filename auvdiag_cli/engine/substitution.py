"""Substituting Control: once a sensor is found defective, the model's output SM_i takes the
place of its reading SS_i from the onset on. This module measures what that substitution is
worth: the track dead-reckoned with the substituted signal against the track with the
failed one (against the truth too where the log has one: `jobs.truth`, after the
diagnosis)."""

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from auvdiag_cli.engine.closed_loop import ClosedLoopReplay
from auvdiag_cli.vehicle.profile import Navigation, Sensor


@dataclass
class Track:
    x_m: np.ndarray
    y_m: np.ndarray

    @property
    def end(self) -> tuple[float, float]:
        return float(self.x_m[-1]), float(self.y_m[-1])

    def distance_to(self, other: "Track") -> float:
        return float(np.hypot(self.x_m[-1] - other.x_m[-1], self.y_m[-1] - other.y_m[-1]))


@dataclass(frozen=True)
class Substitution:
    """SM_i replaces SS_i from ``from_s`` on."""

    signal: str
    from_s: float
    unit: str
    expected_error_rms: float | None     # the model's free-run error on held-out normal logs
    substituted: np.ndarray = field(default_factory=lambda: np.empty(0))
    truth: np.ndarray | None = None           # the true signal, when the log has it
    truth_error_rms: float | None = None      # SM_i − truth after the onset
    failed_error_rms: float | None = None     # SS_i − truth after the onset
    tracks: Mapping[str, Track] = field(default_factory=dict)   # substituted, failed, truth
    closed_loop: ClosedLoopReplay | None = None


def dead_reckon(time_s: np.ndarray, speed: np.ndarray, yaw_rate: np.ndarray) -> Track:
    """Heading from the integrated yaw rate, position from the speed along it; starts at the
    origin heading north (x), as the vehicle's own navigation does."""
    dt = np.diff(time_s, prepend=time_s[0])
    speed, yaw_rate = np.nan_to_num(speed), np.nan_to_num(yaw_rate)
    heading = np.cumsum(yaw_rate * dt)
    return Track(np.cumsum(speed * np.cos(heading) * dt), np.cumsum(speed * np.sin(heading) * dt))


def rms(values: np.ndarray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(np.sqrt(np.mean(finite**2))) if finite.size else None


def substitute(sensor: Sensor, sensor_names: tuple[str, ...], time_s: np.ndarray,
               measured: np.ndarray, modelled: np.ndarray, onset_s: float,
               navigation: Navigation | None, expected_error_rms: float | None
               ) -> Substitution:
    column = sensor_names.index(sensor.name)
    after = time_s >= onset_s
    substituted = measured.copy()
    substituted[after, column] = modelled[after, column]
    tracks = {}
    if navigation is not None:
        speed, rate = sensor_names.index(navigation.speed), sensor_names.index(navigation.yaw_rate)
        tracks["substituted"] = dead_reckon(time_s, substituted[:, speed], substituted[:, rate])
        tracks["failed"] = dead_reckon(time_s, measured[:, speed], measured[:, rate])
    return Substitution(sensor.name, round(onset_s, 3), sensor.unit, expected_error_rms,
                        substituted[:, column], tracks=tracks)
