"""Surge/yaw rigid-body dynamics of a twin-thruster AUV with thruster lag and faults."""

import math
from dataclasses import dataclass, field


@dataclass(frozen=True)
class VehicleParams:
    """Twin-Burger-sized constants (SI units)."""

    mass_kg: float = 60.0
    added_mass_surge_kg: float = 20.0
    inertia_yaw_kgm2: float = 10.0
    added_inertia_yaw_kgm2: float = 5.0
    thruster_max_n: float = 15.0          # forward thrust at command 1
    reverse_thrust_ratio: float = 0.6     # propellers push less in reverse
    thruster_lag_s: float = 0.2           # first-order lag of thrust
    thruster_arm_m: float = 0.3           # lateral offset of each thruster from the centre line
    surge_linear_drag: float = 20.0       # N per m/s
    surge_quadratic_drag: float = 80.0    # N per (m/s)^2
    surge_drag_from_yaw: float = 30.0     # N per (rad/s)^2: turning costs speed (coupling)
    yaw_linear_drag: float = 5.0          # N m per rad/s
    yaw_quadratic_drag: float = 10.0      # N m per (rad/s)^2
    yaw_drag_from_surge: float = 8.0      # N m per (rad/s * m/s): faster means stiffer in yaw

    def thrust_n(self, command: float) -> float:
        """Steady thrust of one thruster: quadratic in the command, weaker in reverse."""
        c = max(-1.0, min(1.0, command))
        thrust = self.thruster_max_n * c * abs(c)
        return thrust if c >= 0 else thrust * self.reverse_thrust_ratio


@dataclass
class VehicleState:
    surge_mps: float = 0.0
    yaw_rate_rps: float = 0.0
    heading_rad: float = 0.0    # clockwise from the x (north) axis
    x_m: float = 0.0            # north
    y_m: float = 0.0            # east
    thrust_n: list[float] = field(default_factory=lambda: [0.0, 0.0])


class TwinThrusterVehicle:
    """Integrates the vehicle with semi-implicit Euler; thruster_gain models actuator faults."""

    def __init__(self, params: VehicleParams) -> None:
        self.params = params
        self.state = VehicleState()
        self.thruster_gain = [1.0, 1.0]

    def step(self, commands: tuple[float, float], dt_s: float,
             disturbance: tuple[float, float] = (0.0, 0.0)) -> None:
        p, s = self.params, self.state
        for i, command in enumerate(commands):
            target = p.thrust_n(command) * self.thruster_gain[i]
            s.thrust_n[i] += (target - s.thrust_n[i]) * min(1.0, dt_s / p.thruster_lag_s)
        u, r = s.surge_mps, s.yaw_rate_rps
        force = (s.thrust_n[0] + s.thrust_n[1] - p.surge_linear_drag * u
                 - p.surge_quadratic_drag * u * abs(u) - p.surge_drag_from_yaw * r * r * _sign(u)
                 + disturbance[0])
        # Thruster 0 (port) pushing alone turns the vehicle to starboard: positive yaw rate.
        torque = (p.thruster_arm_m * (s.thrust_n[0] - s.thrust_n[1])
                  - (p.yaw_linear_drag + p.yaw_drag_from_surge * abs(u)) * r
                  - p.yaw_quadratic_drag * r * abs(r) + disturbance[1])
        s.surge_mps = u + dt_s * force / (p.mass_kg + p.added_mass_surge_kg)
        s.yaw_rate_rps = r + dt_s * torque / (p.inertia_yaw_kgm2 + p.added_inertia_yaw_kgm2)
        s.heading_rad += dt_s * s.yaw_rate_rps
        s.x_m += dt_s * s.surge_mps * math.cos(s.heading_rad)
        s.y_m += dt_s * s.surge_mps * math.sin(s.heading_rad)


def _sign(value: float) -> float:
    return 1.0 if value >= 0 else -1.0
