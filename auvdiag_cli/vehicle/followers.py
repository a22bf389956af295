"""The guidance a profile's controller kind flies a mission's rectangle with: turn-then-go
for a vehicle that sails its path, hover-and-turn for a multirotor that holds its place."""

import math
from collections.abc import Mapping, Sequence
from itertools import pairwise

from auvdiag_cli.vehicle.controller import (
    ControllerGains,
    ControllerSpec,
    Follower,
    FollowerLoops,
    PathFollower,
    wrap_angle,
)

STILL_RPS = 0.03     # a turn is done when the heading is reached and the yaw rate this low


class HeadingFollower(FollowerLoops):
    """Hover-and-turn: turns on the spot to the heading of each leg of the path in turn and
    holds it as long as sailing the leg at the cruise speed would take, at the leg's depth
    (negative: a height). The position is not sensed, so x and y stay at the start."""

    def __init__(self, waypoints: list[tuple[float, float]], gains: ControllerGains,
                 depths_m: Sequence[float] = ()) -> None:
        super().__init__(gains, depths_m)
        corners = [(0.0, 0.0), *waypoints]
        self.legs = [(math.atan2(y1 - y0, x1 - x0), math.hypot(x1 - x0, y1 - y0)
                      / gains.cruise_speed_mps)
                     for (x0, y0), (x1, y1) in pairwise(corners)]
        self.turning = True
        self.held_s = 0.0

    @property
    def finished(self) -> bool:
        return self.target >= len(self.legs)

    def step(self, signals: Mapping[str, float], dt_s: float) -> dict[str, float]:
        g = self.gains
        yaw_rate_rps = signals["yaw_rate"]
        self.heading += yaw_rate_rps * dt_s
        rate_ref = 0.0
        if not self.finished:
            heading, dwell_s = self.legs[self.target]
            error = wrap_angle(heading - self.heading)
            rate_ref = max(-g.turn_rate_rps, min(g.turn_rate_rps, g.heading_gain * error))
            if self.turning:
                self.turning = abs(error) >= g.turn_done_rad or abs(yaw_rate_rps) >= STILL_RPS
            else:
                self.held_s += dt_s
                if self.held_s >= dwell_s:
                    self.target += 1
                    self.turning, self.held_s = True, 0.0
        return {"yaw": self.yaw_effort(rate_ref, yaw_rate_rps, dt_s),
                "heave": self.heave_effort(signals.get("heave", 0.0), dt_s)}


def make_follower(spec: ControllerSpec, waypoints: list[tuple[float, float]],
                  gains: ControllerGains, depths_m: Sequence[float] = ()) -> Follower:
    """The guidance of the profile's controller kind for one mission leg."""
    if spec.kind == "hover-and-turn":
        return HeadingFollower(waypoints, gains, depths_m)
    return PathFollower(waypoints, gains, depths_m)
