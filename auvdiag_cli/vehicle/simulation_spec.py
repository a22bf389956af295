"""A profile's `[simulation]` table: the physics and sensors `auvdiag simulate` flies the
vehicle with. Only the simulator reads it; diagnosis never does (it learns the vehicle)."""

from dataclasses import dataclass, field

from auvdiag_cli.vehicle.toml_reader import TableReader, positive
from auvdiag_errors import ProfileError

# Body-frame degrees of freedom the simulator knows; heave is positive down. Roll and pitch
# are rates only: the attitude they integrate to does not feed back (a multirotor's
# attitude hold keeps it small).
DOFS = ("surge", "sway", "heave", "yaw", "roll", "pitch")
TRUTH_COLUMNS = {"surge": "surge_mps", "sway": "sway_mps", "heave": "heave_mps",
                 "yaw": "yaw_rate_rps", "roll": "roll_rate_rps", "pitch": "pitch_rate_rps"}


@dataclass(frozen=True)
class DofPhysics:
    """One degree of freedom: inertia including added mass (kg, or kg m² for yaw), drag
    a·v + b·v|v|, a constant force (net buoyancy on heave), couplings from the others
    (``cross_quadratic[o]``·v_o² against the motion, ``cross_linear[o]``·|v_o|·v), and the
    scale of the slow random disturbance."""

    inertia: float
    linear_drag: float
    quadratic_drag: float
    constant_force: float = 0.0
    cross_quadratic: dict[str, float] = field(default_factory=dict)
    cross_linear: dict[str, float] = field(default_factory=dict)
    disturbance: float = 0.0


@dataclass(frozen=True)
class ThrusterPhysics:
    """Thrust = max_thrust_n · c|c| (times reverse_ratio backwards) reached with a first-order
    lag; ``effect[dof]`` is the force (N) or moment (N m) per newton of thrust."""

    command: str
    max_thrust_n: float
    reverse_ratio: float
    lag_s: float
    effect: dict[str, float]

    def steady_thrust_n(self, command: float) -> float:
        c = max(-1.0, min(1.0, command))
        thrust = self.max_thrust_n * c * abs(c)
        return thrust if c >= 0 else thrust * self.reverse_ratio


@dataclass(frozen=True)
class SensorPhysics:
    """What a sensor measures and how: its degree of freedom (times ``scale``: -1 for a climb
    rate, up positive), rate, white noise (1 σ, in the sensor's unit) and quantisation step."""

    sensor: str
    measures: str
    rate_hz: float
    noise: float
    quantum: float
    scale: float = 1.0


@dataclass(frozen=True)
class SimulationSpec:
    dofs: dict[str, DofPhysics]                 # in the vehicle's order
    thrusters: tuple[ThrusterPhysics, ...]      # in command order
    sensors: tuple[SensorPhysics, ...]          # in sensor order
    mission_depths_m: tuple[float, ...] = ()    # depth of successive legs of simulated missions


def _coupling(reader: TableReader, name: str, dofs: list[str]) -> dict[str, float]:
    if name not in reader.table:
        return {}
    table = reader.sub(name)
    for other in table.names():
        if other not in dofs:
            raise ProfileError(f"key '{table.key(other)}' names no simulated degree of freedom")
    return {other: table.get(other, float) for other in table.table}


def _dof(reader: TableReader, dofs: list[str]) -> DofPhysics:
    return DofPhysics(
        positive(reader, "inertia"), reader.get("linear_drag", float),
        reader.get("quadratic_drag", float), reader.get("constant_force", float, 0.0),
        _coupling(reader, "cross_quadratic", dofs), _coupling(reader, "cross_linear", dofs),
        reader.get("disturbance", float, 0.0))


def parse_simulation(reader: TableReader, command_names: list[str],
                     sensor_names: list[str]) -> SimulationSpec:
    dof_table = reader.sub("dofs")
    dofs = dof_table.names()
    unknown = [d for d in dofs if d not in DOFS]
    if unknown or not dofs:
        raise ProfileError(f"key '{dof_table.where}' must name some of {', '.join(DOFS)}")
    physics = {name: _dof(dof_table.sub(name), dofs) for name in dofs}

    thrusters = []
    for row in reader.items("thrusters"):
        effect = _coupling(row, "effect", dofs)
        thrusters.append(ThrusterPhysics(
            row.get("command", str), positive(row, "max_thrust_n"),
            positive(row, "reverse_ratio"), positive(row, "lag_s"), effect))
    if [t.command for t in thrusters] != command_names:
        raise ProfileError(f"key '{reader.key('thrusters')}' must describe the commands "
                           f"{', '.join(command_names)} in that order")
    sensors = []
    for row in reader.items("sensors"):
        measures = row.get("measures", str)
        if measures not in dofs:
            raise ProfileError(f"key '{row.key('measures')}' names no simulated degree of "
                               f"freedom: {measures!r}")
        sensors.append(SensorPhysics(row.get("sensor", str), measures, positive(row, "rate_hz"),
                                     row.get("noise", float), positive(row, "quantum"),
                                 row.get("scale", float, 1.0)))
    if [s.sensor for s in sensors] != sensor_names:
        raise ProfileError(f"key '{reader.key('sensors')}' must describe the sensors "
                           f"{', '.join(sensor_names)} in that order")
    depths = reader.get("mission_depths_m", list, [])
    return SimulationSpec(physics, tuple(thrusters), tuple(sensors),
                          tuple(float(d) for d in depths))
