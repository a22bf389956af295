"""Rigid-body dynamics of a thruster-driven vehicle in the degrees of freedom its profile's
`[simulation]` table describes (surge, sway, heave, yaw), with thruster lag and faults."""

import math

from auvdiag_cli.vehicle.simulation_spec import SimulationSpec


class Vehicle:
    """Integrates the vehicle with semi-implicit Euler; ``thruster_gain`` models actuator
    faults. ``velocity[dof]`` is in the body frame; heading, x (north), y (east) and depth
    (down) in the world frame."""

    def __init__(self, spec: SimulationSpec) -> None:
        self.spec = spec
        self.velocity = dict.fromkeys(spec.dofs, 0.0)
        self.thrust_n = [0.0] * len(spec.thrusters)
        self.thruster_gain = [1.0] * len(spec.thrusters)
        self.heading_rad = self.x_m = self.y_m = self.depth_m = 0.0

    def step(self, commands: tuple[float, ...], dt_s: float,
             disturbance: dict[str, float] | None = None) -> None:
        for i, (thruster, command) in enumerate(zip(self.spec.thrusters, commands, strict=True)):
            target = thruster.steady_thrust_n(command) * self.thruster_gain[i]
            self.thrust_n[i] += (target - self.thrust_n[i]) * min(1.0, dt_s / thruster.lag_s)
        v = self.velocity
        accelerations = {}
        for dof, p in self.spec.dofs.items():
            own = v[dof]
            force = sum(t.effect.get(dof, 0.0) * self.thrust_n[i]
                        for i, t in enumerate(self.spec.thrusters))
            force -= (p.linear_drag + sum(c * abs(v[o]) for o, c in p.cross_linear.items())) * own
            force -= p.quadratic_drag * own * abs(own)
            force -= sum(c * v[o] * v[o] for o, c in p.cross_quadratic.items()) * _sign(own)
            force += p.constant_force + (disturbance or {}).get(dof, 0.0)
            accelerations[dof] = force / p.inertia
        for dof, acceleration in accelerations.items():
            v[dof] += dt_s * acceleration
        self.heading_rad += dt_s * v.get("yaw", 0.0)
        surge, sway = v.get("surge", 0.0), v.get("sway", 0.0)
        cos, sin = math.cos(self.heading_rad), math.sin(self.heading_rad)
        self.x_m += dt_s * (surge * cos - sway * sin)
        self.y_m += dt_s * (surge * sin + sway * cos)
        self.depth_m += dt_s * v.get("heave", 0.0)


def _sign(value: float) -> float:
    return 1.0 if value >= 0 else -1.0
