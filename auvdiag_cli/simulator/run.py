"""Run a scenario: physics at 100 Hz, controller and commands at 10 Hz, each sensor at the
rate its profile's `[simulation]` table gives, with its own phase, noise, quantisation and
receive jitter."""

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from auvdiag_cli.simulator.faults import Fault
from auvdiag_cli.simulator.scenarios import Phase, Scenario
from auvdiag_cli.simulator.vehicle import Vehicle
from auvdiag_cli.vehicle.controller import VehicleController, rectangle_waypoints
from auvdiag_cli.vehicle.followers import make_follower
from auvdiag_cli.vehicle.profile import Profile

if TYPE_CHECKING:
    import pandas as pd
from auvdiag_cli.vehicle.simulation_spec import TRUTH_COLUMNS, SensorPhysics, SimulationSpec

PHYSICS_DT_S = 0.01
CONTROL_EVERY = 10      # physics ticks per command (10 Hz)
RECEIVE_JITTER_S = 0.002
SETTLE_AFTER_MISSION_S = 5.0
LOG_EPOCH_NS = 1_795_341_600_000_000_000   # 2026-11-22T10:00:00Z


@dataclass
class Stream:
    """Messages of one topic: receive times (s from the log start) and values."""

    times_s: list[float] = field(default_factory=list)
    values: list[tuple[float, ...]] = field(default_factory=list)

    def add(self, time_s: float, *values: float) -> None:
        self.times_s.append(time_s)
        self.values.append(values)


@dataclass
class SimulatedDive:
    scenario: Scenario
    seed: int
    commands: Stream
    sensors: dict[str, Stream]          # by sensor name
    markers: list[tuple[float, str]]
    phase_starts_s: list[tuple[str, float]]
    truth: "pd.DataFrame"
    start_ns: int = LOG_EPOCH_NS
    # The mission plans as the vehicle had them: start time, waypoints, cruise speed.
    missions: list[dict[str, object]] = field(default_factory=list)

    @property
    def duration_s(self) -> float:
        return float(self.truth["t_s"].iloc[-1])

    def last_works_s(self, actuator: int, span_s: float) -> float:
        """The start of the last ``span_s`` over which the actuator's true thrust averages
        at least its mean over the mission (in size): where a fault that begins ``span_s``
        before it last works still has work to show on. A fault's time before the log's
        end says little: a ROV's horizontal thrusters hold station at a mission's end on a
        few hundredths of a newton, and a stop there changes nothing any log could show."""
        times = self.truth["t_s"].to_numpy()
        thrust = np.abs(self.truth[f"thrust_{actuator}_n"].to_numpy())
        steps = max(1, round(span_s / float(np.median(np.diff(times)))))
        over_span = np.convolve(thrust, np.ones(steps) / steps, mode="valid")
        working = np.flatnonzero(over_span >= thrust.mean())
        return float(times[working[-1]]) if working.size else self.duration_s - span_s


class _Noise:
    """Pre-drawn noise so the tick loop stays cheap."""

    def __init__(self, rng: np.random.Generator, scale: float, size: int = 4096) -> None:
        self.rng, self.scale, self.size = rng, scale, size
        self.buffer = rng.normal(0.0, scale, size)
        self.next = 0

    def draw(self) -> float:
        if self.next == self.size:
            self.buffer, self.next = self.rng.normal(0.0, self.scale, self.size), 0
        self.next += 1
        return float(self.buffer[self.next - 1])


def _quantise(value: float, quantum: float) -> float:
    return round(value / quantum) * quantum


class _SensorChannel:
    """One simulated sensor: when it samples, its noise, and its last reading."""

    def __init__(self, physics: SensorPhysics, component: str, every: int, noise: "_Noise"
                 ) -> None:
        self.name, self.component, self.every = physics.sensor, component, every
        self.noise, self.quantum, self.measures = noise, physics.quantum, physics.measures
        self.scale = physics.scale
        self.last = 0.0


class _Dive:
    """Mutable state of one simulation run."""

    def __init__(self, scenario: Scenario, profile: Profile, spec: SimulationSpec,
                 seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.scenario, self.profile, self.spec, self.fault = scenario, profile, spec, scenario.fault
        self.vehicle = Vehicle(spec)
        self.rng = rng
        self.channels = [
            _SensorChannel(physics, profile.sensor(physics.sensor).component,
                           max(1, round(1.0 / (physics.rate_hz * PHYSICS_DT_S))),
                           _Noise(rng, physics.noise))
            for physics in spec.sensors]
        self.disturbance_noise = {dof: _Noise(rng, p.disturbance) for dof, p in spec.dofs.items()}
        self.disturbance = dict.fromkeys(spec.dofs, 0.0)
        self.tick = 0
        self.command: tuple[float, ...] = (0.0,) * len(profile.commands)
        streams = {channel.name: Stream() for channel in self.channels}
        import pandas as pd  # the simulator's truth table; diagnosis needs no pandas

        self.out = SimulatedDive(scenario, seed, Stream(), streams, [], [], pd.DataFrame())
        self.truth_rows: list[tuple[float, ...]] = []

    @property
    def time_s(self) -> float:
        return self.tick * PHYSICS_DT_S

    def jitter(self) -> float:
        return float(self.rng.uniform(0.0, RECEIVE_JITTER_S))

    def fault_over(self) -> bool:
        fault = self.fault
        return fault is not None and self.time_s >= fault.onset_s + self.scenario.run_after_fault_s

    def sensor(self, component: str, true_value: float) -> float:
        if self.fault is None:
            return true_value
        return self.fault.sensor_reading(component, true_value, self.time_s)

    def advance(self, controller: VehicleController | None, dms_levels: tuple[float, ...] | None
                ) -> None:
        """One physics tick, publishing whatever is due at this instant."""
        t = self.time_s
        vehicle = self.vehicle
        if self.tick % CONTROL_EVERY == 0:
            if controller is not None:
                readings = [channel.last for channel in self.channels]
                self.command = tuple(float(c) for c in controller.step(
                    readings, CONTROL_EVERY * PHYSICS_DT_S))
            elif dms_levels is not None:
                self.command = dms_levels
            self.out.commands.add(t + self.jitter(), *self.command)
            self.truth_rows.append((t, *vehicle.velocity.values(), vehicle.heading_rad,
                                    vehicle.x_m, vehicle.y_m, vehicle.depth_m, *vehicle.thrust_n,
                                    *(channel.last for channel in self.channels)))
        for channel in self.channels:
            if self.tick % channel.every == channel.every // 2:
                reading = channel.scale * vehicle.velocity[channel.measures] + channel.noise.draw()
                channel.last = _quantise(self.sensor(channel.component, reading),
                                         channel.quantum)
                self.out.sensors[channel.name].add(t + self.jitter(), channel.last)
        if self.fault is not None:
            vehicle.thruster_gain = [self.fault.thruster_gain(c.component, t)
                                     for c in self.profile.commands]
        # Slow, small Ornstein-Uhlenbeck disturbance: the tank is steady, not perfectly still.
        decay = PHYSICS_DT_S / 2.0
        for dof, noise in self.disturbance_noise.items():
            self.disturbance[dof] += -decay * self.disturbance[dof] + 0.1 * noise.draw()
        vehicle.step(self.command, PHYSICS_DT_S, self.disturbance)
        self.tick += 1

    def run_phase(self, phase: Phase) -> None:
        self.out.markers.append((self.time_s + self.jitter(), phase.name))
        self.out.phase_starts_s.append((phase.name, self.time_s))
        if phase.excitation is not None:
            self._run_excitation(phase.excitation.duration_s)
        elif phase.mission is None:
            self._run_dms(phase.name)
        else:
            self._run_mission(phase)

    def _run_excitation(self, duration_s: float) -> None:
        end = self.time_s + duration_s
        while self.time_s < end and not self.fault_over():
            levels = tuple(float(v) for v in self.rng.uniform(-1.0, 1.0, len(self.command)))
            for _ in range(round(float(self.rng.uniform(1.0, 4.0)) / PHYSICS_DT_S)):
                self.advance(None, levels)

    def _run_dms(self, name: str) -> None:
        for duration_s, levels in self.profile.dms[name].steps:
            for _ in range(round(duration_s / PHYSICS_DT_S)):
                if self.fault_over():
                    return
                self.advance(None, levels)

    def _run_mission(self, phase: Phase) -> None:
        spec = phase.mission
        assert spec is not None
        waypoints = rectangle_waypoints(spec.length_m, spec.width_m, spec.clockwise)
        profile = self.profile
        if profile.controller is None:
            raise ValueError(f"profile {profile.name!r} describes no [controller] to fly "
                             "missions with")
        gains = profile.controller.gains_for(spec.cruise_speed_mps)
        depths = self.spec.mission_depths_m
        depths_m = [depths[i % len(depths)] for i in range(len(waypoints))] if depths else []
        follower = make_follower(profile.controller, waypoints, gains, depths_m)
        controller = VehicleController(profile.controller, profile.sensor_names,
                                       profile.command_names, follower)
        plan: dict[str, object] = {"start_s": round(self.time_s, 6), "waypoints": waypoints,
                                   "cruise_speed_mps": spec.cruise_speed_mps}
        if depths_m:
            plan["depths_m"] = depths_m
        self.out.missions.append(plan)
        # The controller's navigation starts where the vehicle is, in its own frame.
        follower.heading = 0.0
        start = self.time_s
        settle_ticks = round(SETTLE_AFTER_MISSION_S / PHYSICS_DT_S)
        while settle_ticks > 0 and self.time_s - start < spec.max_duration_s:
            if self.fault_over():
                return
            self.advance(controller, None)
            if follower.finished:
                settle_ticks -= 1

    def finish(self) -> SimulatedDive:
        columns = ["t_s", *(TRUTH_COLUMNS[d] for d in self.spec.dofs), "heading_rad", "x_m",
                   "y_m", "depth_m", *(f"thrust_{i}_n" for i in range(len(self.spec.thrusters))),
                   *(f"{c.name}_reading" for c in self.channels)]
        import pandas as pd

        self.out.truth = pd.DataFrame(self.truth_rows, columns=columns)
        return self.out


def simulate(scenario: Scenario, profile: Profile, seed: int = 0,
             start_ns: int = LOG_EPOCH_NS) -> SimulatedDive:
    """Fly ``scenario`` once; ``seed`` fixes every noise draw; the log's clock starts at
    ``start_ns`` (Unix time)."""
    if profile.simulation is None:
        raise ValueError(f"profile {profile.name!r} has no [simulation] table: nothing "
                         "describes how to fly it")
    if profile.inputs:
        raise ValueError(f"profile {profile.name!r} declares measured inputs "
                         f"({', '.join(profile.input_names)}): the simulator does not model them")
    missing = [p.name for p in scenario.phases
               if p.mission is None and p.excitation is None and p.name not in profile.dms]
    if missing:
        raise KeyError(f"profile {profile.name!r} defines no DMS {', '.join(missing)}")
    if scenario.fault is not None:
        scenario.fault.check(profile)
    dive = _Dive(scenario, profile, profile.simulation, seed)
    for phase in scenario.phases:
        dive.run_phase(phase)
        if dive.fault_over():
            break
    result = dive.finish()
    result.start_ns = start_ns
    return result


def fault_summary(fault: Fault | None) -> dict[str, object] | None:
    if fault is None:
        return None
    return {"component": fault.component, "kind": fault.kind, "onset_s": fault.onset_s,
            "severity": fault.severity if fault.kind in ("weak", "bias", "drift") else None}

