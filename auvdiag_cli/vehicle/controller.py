"""The vehicle's own mission controller: dead-reckoning navigation from its sensors, a
turn-then-go waypoint guidance, PI loops on speed (flow sensor) and yaw rate (yaw-rate
sensor), and for vehicles that keep depth a depth loop on the integrated heave rate. Because
the loops are closed on the sensors, a sensor fault changes the commands, as it did on the
real vehicle. The loops output efforts (surge, yaw, heave) that the profile's mix turns into
actuator commands."""

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

EFFORTS = ("surge", "yaw", "heave")


@dataclass(frozen=True)
class ControllerGains:
    cruise_speed_mps: float = 0.125
    speed_ramp_mps2: float = 0.03        # how fast the speed reference rises after a turn
    turn_rate_rps: float = 0.2           # yaw-rate limit while turning on the spot
    track_rate_rps: float = 0.08         # yaw-rate limit while going straight
    heading_gain: float = 0.8            # yaw-rate reference per rad of heading error
    turn_done_rad: float = math.radians(4.0)
    arrive_m: float = 0.15
    speed_kp: float = 2.0
    speed_ki: float = 1.0
    yaw_kp: float = 2.0
    yaw_ki: float = 1.5
    integral_limit: float = 0.5
    # Nominal inverse steady-state maps used as feed-forward (from the design model).
    speed_feedforward: float = 1.2       # common command per sqrt(m/s)
    yaw_feedforward: float = 1.0         # differential command per sqrt(rad/s)
    depth_gain: float = 0.5              # heave-rate reference per m of depth error
    heave_rate_limit_mps: float = 0.15
    heave_kp: float = 2.0
    heave_ki: float = 1.0
    heave_feedforward: float = 1.0       # heave command per sqrt(m/s)


@dataclass(frozen=True)
class ControllerSpec:
    """The vehicle's own mission controller, for closed-loop replays: its kind (the only one
    implemented is "turn-then-go", see auvdiag_cli.vehicle.controller), the sensors it is fed (a
    heave-rate sensor when it also keeps depth), how its surge/yaw/heave efforts are mixed
    onto the commands, and gains that differ from the defaults."""

    kind: str
    speed: str
    yaw_rate: str
    mix: dict[str, dict[str, float]]     # command -> effort (surge, yaw, heave) -> factor
    gains: ControllerGains                 # the profile's, over the defaults
    heave: str | None = None

    def gains_for(self, cruise_speed_mps: float | None = None) -> ControllerGains:
        """The gains, with a mission's own cruise speed where it sets one."""
        if cruise_speed_mps is None:
            return self.gains
        return replace(self.gains, cruise_speed_mps=cruise_speed_mps)



def wrap_angle(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _signed_sqrt(value: float) -> float:
    return math.copysign(math.sqrt(abs(value)), value)


def _clip(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


class PathFollower:
    """Steps at the control rate; returns the efforts {surge, yaw, heave}. ``depths_m`` gives
    the depth to hold on the way to each waypoint (none: the heave effort stays zero)."""

    def __init__(self, waypoints: list[tuple[float, float]], gains: ControllerGains,
                 depths_m: Sequence[float] = ()) -> None:
        self.waypoints = waypoints
        self.depths_m = list(depths_m)
        self.gains = gains
        self.target = 0
        self.turning = True
        self.x = self.y = self.heading = self.depth = 0.0
        self.speed_ref = 0.0
        self.speed_integral = self.yaw_integral = self.heave_integral = 0.0

    @property
    def finished(self) -> bool:
        return self.target >= len(self.waypoints)

    def step(self, flow_mps: float, yaw_rate_rps: float, dt_s: float, heave_mps: float = 0.0
             ) -> dict[str, float]:
        g = self.gains
        self.heading += yaw_rate_rps * dt_s
        self.x += flow_mps * math.cos(self.heading) * dt_s
        self.y += flow_mps * math.sin(self.heading) * dt_s
        self.depth += heave_mps * dt_s
        rate_ref, speed_target = 0.0, 0.0
        if not self.finished:
            wx, wy = self.waypoints[self.target]
            distance = math.hypot(wx - self.x, wy - self.y)
            error = wrap_angle(math.atan2(wy - self.y, wx - self.x) - self.heading)
            if self.turning:
                rate_ref = _clip(g.heading_gain * error, g.turn_rate_rps)
                if abs(error) < g.turn_done_rad and abs(yaw_rate_rps) < 0.03:
                    self.turning = False
            else:
                rate_ref = _clip(g.heading_gain * error, g.track_rate_rps)
                speed_target = g.cruise_speed_mps * min(1.0, distance / 0.6) * max(
                    0.0, math.cos(error))
                if distance < g.arrive_m or abs(error) > math.pi / 2:
                    self.target += 1
                    self.turning = True
        ramp = g.speed_ramp_mps2 * dt_s
        self.speed_ref = min(speed_target, self.speed_ref + ramp)
        speed_error = self.speed_ref - flow_mps
        rate_error = rate_ref - yaw_rate_rps
        self.speed_integral = _clip(self.speed_integral + speed_error * dt_s, g.integral_limit)
        self.yaw_integral = _clip(self.yaw_integral + rate_error * dt_s, g.integral_limit)
        common = (g.speed_feedforward * _signed_sqrt(self.speed_ref) + g.speed_kp * speed_error
                  + g.speed_ki * self.speed_integral)
        differential = (g.yaw_feedforward * _signed_sqrt(rate_ref) + g.yaw_kp * rate_error
                        + g.yaw_ki * self.yaw_integral)
        return {"surge": common, "yaw": differential, "heave": self._heave_effort(heave_mps,
                                                                                   dt_s)}

    def _heave_effort(self, heave_mps: float, dt_s: float) -> float:
        if not self.depths_m:
            return 0.0
        g = self.gains
        target = self.depths_m[min(self.target, len(self.depths_m) - 1)]
        heave_ref = _clip(g.depth_gain * (target - self.depth), g.heave_rate_limit_mps)
        heave_error = heave_ref - heave_mps
        self.heave_integral = _clip(self.heave_integral + heave_error * dt_s, g.integral_limit)
        return (g.heave_feedforward * _signed_sqrt(heave_ref) + g.heave_kp * heave_error
                + g.heave_ki * self.heave_integral)


def mix_commands(mix: Mapping[str, Mapping[str, float]], command_names: Sequence[str],
                 efforts: Mapping[str, float]) -> np.ndarray:
    """Actuator commands (clipped to ±1) from the efforts through the profile's mix; commands
    the mix does not name stay at zero."""
    commands = np.zeros(len(command_names))
    for index, name in enumerate(command_names):
        factors = mix.get(name, {})
        commands[index] = _clip(sum(f * efforts[e] for e, f in factors.items()), 1.0)
    return commands


class VehicleController:
    """The profile's controller on a vehicle: sensor readings in (profile order), actuator
    commands out (profile order)."""

    def __init__(self, spec: ControllerSpec, sensor_names: Sequence[str],
                 command_names: Sequence[str], follower: PathFollower) -> None:
        self.spec, self.follower, self.command_names = spec, follower, command_names
        self.speed = sensor_names.index(spec.speed)
        self.yaw_rate = sensor_names.index(spec.yaw_rate)
        self.heave = None if spec.heave is None else sensor_names.index(spec.heave)

    def step(self, readings: Sequence[float] | np.ndarray, dt_s: float) -> np.ndarray:
        heave = 0.0 if self.heave is None else float(readings[self.heave])
        efforts = self.follower.step(float(readings[self.speed]), float(readings[self.yaw_rate]),
                                     dt_s, heave)
        return mix_commands(self.spec.mix, self.command_names, efforts)


def rectangle_waypoints(length_m: float, width_m: float, clockwise: bool
                        ) -> list[tuple[float, float]]:
    """Corners of a rectangle starting at the origin heading north; clockwise = right turns."""
    side = width_m if clockwise else -width_m
    return [(length_m, 0.0), (length_m, side), (0.0, side), (0.0, 0.0)]
