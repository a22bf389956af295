"""The vehicle's own mission controller: dead-reckoning navigation from its sensors, a
turn-then-go waypoint guidance, PI loops on speed (flow sensor) and yaw rate (yaw-rate
sensor), for vehicles that keep depth a depth loop on the integrated heave rate, for
vehicles that must hold their attitude (multirotors) PI loops holding the roll and pitch
rates at zero, and for vehicles that can push sideways (vectored ROVs) a PI loop holding the
sideways velocity at zero. Because the loops are closed on the sensors, a sensor fault
changes the commands, as it did on the real vehicle, and a weak actuator is driven harder.
The loops output efforts (surge, yaw, heave, roll, pitch, sway) that the profile's mix turns
into actuator commands."""

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

EFFORTS = ("surge", "yaw", "heave", "roll", "pitch", "sway")
CONTROLLER_KINDS = ("turn-then-go", "hover-and-turn")


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
    heave_bias: float = 0.0              # heave effort that holds the vehicle up (a hover)
    rate_hold_kp: float = 0.02           # roll and pitch rate holds, effort per rad/s
    rate_hold_ki: float = 0.1
    sway_hold_kp: float = 0.5            # sideways velocity hold, effort per m/s
    sway_hold_ki: float = 0.5


@dataclass(frozen=True)
class ControllerSpec:
    """The vehicle's own mission controller, for closed-loop replays: its kind
    ("turn-then-go", a vehicle that sails its path; "hover-and-turn", a multirotor that holds
    its place and turns to each leg's heading), the sensors it is fed (a heave-rate sensor
    when it also keeps depth or height, roll and pitch rates when it holds its attitude, the
    sideways velocity when it holds its track), how its efforts are mixed onto the commands,
    and gains that differ from the defaults."""

    kind: str
    speed: str | None                    # none for a vehicle that does not sail its path
    yaw_rate: str
    mix: dict[str, dict[str, float]]     # command -> effort (EFFORTS) -> factor
    gains: ControllerGains                 # the profile's, over the defaults
    heave: str | None = None
    heave_sign: float = 1.0              # -1: the heave sensor reads up positive (a climb)
    roll_rate: str | None = None
    pitch_rate: str | None = None
    sway: str | None = None

    @property
    def held_efforts(self) -> tuple[str, ...]:
        """The efforts a loop of this controller drives (the others stay at zero)."""
        held = {"surge": self.speed, "yaw": self.yaw_rate, "heave": self.heave,
                "roll": self.roll_rate, "pitch": self.pitch_rate, "sway": self.sway}
        return tuple(effort for effort in EFFORTS if held[effort] is not None)

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


class FollowerLoops:
    """The loops every follower closes: yaw rate to a reference, and the depth (or height)
    of the leg under way through the integrated heave rate."""

    def __init__(self, gains: ControllerGains, depths_m: Sequence[float]) -> None:
        self.gains = gains
        self.depths_m = list(depths_m)
        self.target = 0
        self.x = self.y = self.heading = self.depth = 0.0
        self.yaw_integral = self.heave_integral = 0.0

    def yaw_effort(self, rate_ref: float, yaw_rate_rps: float, dt_s: float) -> float:
        g = self.gains
        rate_error = rate_ref - yaw_rate_rps
        self.yaw_integral = _clip(self.yaw_integral + rate_error * dt_s, g.integral_limit)
        return (g.yaw_feedforward * _signed_sqrt(rate_ref) + g.yaw_kp * rate_error
                + g.yaw_ki * self.yaw_integral)

    def heave_effort(self, heave_mps: float, dt_s: float) -> float:
        g = self.gains
        self.depth += heave_mps * dt_s
        if not self.depths_m:
            return g.heave_bias
        target = self.depths_m[min(self.target, len(self.depths_m) - 1)]
        heave_ref = _clip(g.depth_gain * (target - self.depth), g.heave_rate_limit_mps)
        heave_error = heave_ref - heave_mps
        self.heave_integral = _clip(self.heave_integral + heave_error * dt_s, g.integral_limit)
        return (g.heave_bias + g.heave_feedforward * _signed_sqrt(heave_ref)
                + g.heave_kp * heave_error + g.heave_ki * self.heave_integral)


class PathFollower(FollowerLoops):
    """Turn-then-go: steps at the control rate; returns the efforts {surge, yaw, heave}.
    ``depths_m`` gives the depth to hold on the way to each waypoint (none: the heave effort
    stays at its bias)."""

    def __init__(self, waypoints: list[tuple[float, float]], gains: ControllerGains,
                 depths_m: Sequence[float] = ()) -> None:
        super().__init__(gains, depths_m)
        self.waypoints = waypoints
        self.turning = True
        self.speed_ref = 0.0
        self.speed_integral = 0.0

    @property
    def finished(self) -> bool:
        return self.target >= len(self.waypoints)

    def step(self, signals: Mapping[str, float], dt_s: float) -> dict[str, float]:
        g = self.gains
        flow_mps, yaw_rate_rps = signals["speed"], signals["yaw_rate"]
        self.heading += yaw_rate_rps * dt_s
        self.x += flow_mps * math.cos(self.heading) * dt_s
        self.y += flow_mps * math.sin(self.heading) * dt_s
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
        self.speed_integral = _clip(self.speed_integral + speed_error * dt_s, g.integral_limit)
        common = (g.speed_feedforward * _signed_sqrt(self.speed_ref) + g.speed_kp * speed_error
                  + g.speed_ki * self.speed_integral)
        return {"surge": common, "yaw": self.yaw_effort(rate_ref, yaw_rate_rps, dt_s),
                "heave": self.heave_effort(signals.get("heave", 0.0), dt_s)}


class ZeroHold:
    """PI loop holding a rate at zero: a multirotor's roll or pitch rate (its attitude
    hold), a vectored ROV's sideways velocity (its track). The integral carries the steady
    torque or force a weak actuator leaves unbalanced."""

    def __init__(self, kp: float, ki: float, integral_limit: float) -> None:
        self.kp, self.ki, self.integral_limit = kp, ki, integral_limit
        self.integral = 0.0

    def step(self, rate: float, dt_s: float) -> float:
        self.integral = _clip(self.integral - rate * dt_s, self.integral_limit)
        return -self.kp * rate + self.ki * self.integral


class Follower(Protocol):
    """Guidance at the control rate: signals by role in, efforts out."""

    x: float
    y: float
    heading: float

    @property
    def finished(self) -> bool: ...

    def step(self, signals: Mapping[str, float], dt_s: float) -> dict[str, float]: ...


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
                 command_names: Sequence[str], follower: Follower) -> None:
        self.spec, self.follower, self.command_names = spec, follower, command_names
        roles = {"speed": spec.speed, "yaw_rate": spec.yaw_rate, "heave": spec.heave}
        self.roles = {role: sensor_names.index(name) for role, name in roles.items()
                      if name is not None}
        g = spec.gains
        holds = (("roll", spec.roll_rate, g.rate_hold_kp, g.rate_hold_ki),
                 ("pitch", spec.pitch_rate, g.rate_hold_kp, g.rate_hold_ki),
                 ("sway", spec.sway, g.sway_hold_kp, g.sway_hold_ki))
        self.holds = {effort: (sensor_names.index(name),
                               ZeroHold(kp, ki, g.integral_limit))
                      for effort, name, kp, ki in holds if name is not None}

    def step(self, readings: Sequence[float] | np.ndarray, dt_s: float) -> np.ndarray:
        signals = {role: float(readings[index]) for role, index in self.roles.items()}
        if "heave" in signals:
            signals["heave"] *= self.spec.heave_sign
        efforts = dict.fromkeys(EFFORTS, 0.0) | self.follower.step(signals, dt_s)
        for effort, (index, hold) in self.holds.items():
            efforts[effort] = hold.step(float(readings[index]), dt_s)
        return mix_commands(self.spec.mix, self.command_names, efforts)


def rectangle_waypoints(length_m: float, width_m: float, clockwise: bool
                        ) -> list[tuple[float, float]]:
    """Corners of a rectangle starting at the origin heading north; clockwise = right turns."""
    side = width_m if clockwise else -width_m
    return [(length_m, 0.0), (length_m, side), (0.0, side), (0.0, 0.0)]
