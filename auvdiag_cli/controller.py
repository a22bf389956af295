"""The vehicle's own mission controller: dead-reckoning navigation from its sensors, a
turn-then-go waypoint guidance, and PI loops on speed (flow sensor) and yaw rate (yaw-rate
sensor). Because the loops are closed on the sensors, a sensor fault changes the commands,
as it did on the real vehicle."""

import math
from dataclasses import dataclass


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


def wrap_angle(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _signed_sqrt(value: float) -> float:
    return math.copysign(math.sqrt(abs(value)), value)


def _clip(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


class PathFollower:
    """Steps at the control rate; returns (thruster_0, thruster_1) commands."""

    def __init__(self, waypoints: list[tuple[float, float]], gains: ControllerGains) -> None:
        self.waypoints = waypoints
        self.gains = gains
        self.target = 0
        self.turning = True
        self.x = self.y = self.heading = 0.0
        self.speed_ref = 0.0
        self.speed_integral = self.yaw_integral = 0.0

    @property
    def finished(self) -> bool:
        return self.target >= len(self.waypoints)

    def step(self, flow_mps: float, yaw_rate_rps: float, dt_s: float) -> tuple[float, float]:
        g = self.gains
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
        rate_error = rate_ref - yaw_rate_rps
        self.speed_integral = _clip(self.speed_integral + speed_error * dt_s, g.integral_limit)
        self.yaw_integral = _clip(self.yaw_integral + rate_error * dt_s, g.integral_limit)
        common = (g.speed_feedforward * _signed_sqrt(self.speed_ref) + g.speed_kp * speed_error
                  + g.speed_ki * self.speed_integral)
        differential = (g.yaw_feedforward * _signed_sqrt(rate_ref) + g.yaw_kp * rate_error
                        + g.yaw_ki * self.yaw_integral)
        return _clip(common + differential, 1.0), _clip(common - differential, 1.0)


def rectangle_waypoints(length_m: float, width_m: float, clockwise: bool
                        ) -> list[tuple[float, float]]:
    """Corners of a rectangle starting at the origin heading north; clockwise = right turns."""
    side = width_m if clockwise else -width_m
    return [(length_m, 0.0), (length_m, side), (0.0, side), (0.0, 0.0)]
