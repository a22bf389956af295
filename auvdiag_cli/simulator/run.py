"""Run a scenario: physics at 100 Hz, controller and commands at 10 Hz, flow sensor at
10 Hz, IMU at 50 Hz, each with its own phase, noise, quantisation and receive jitter."""

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from auvdiag_cli.controller import ControllerGains, PathFollower, rectangle_waypoints
from auvdiag_cli.profile import Profile
from auvdiag_cli.simulator.faults import Fault
from auvdiag_cli.simulator.scenarios import Phase, Scenario
from auvdiag_cli.simulator.vehicle import TwinThrusterVehicle, VehicleParams

PHYSICS_DT_S = 0.01
CONTROL_EVERY = 10      # physics ticks per command (10 Hz)
FLOW_EVERY = 10         # 10 Hz
IMU_EVERY = 2           # 50 Hz
FLOW_NOISE_MPS, FLOW_QUANTUM_MPS = 0.004, 0.001
GYRO_NOISE_RPS, GYRO_QUANTUM_RPS = 0.008, 0.0005
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
    flow: Stream
    imu: Stream
    markers: list[tuple[float, str]]
    phase_starts_s: list[tuple[str, float]]
    truth: pd.DataFrame
    start_ns: int = LOG_EPOCH_NS
    # The mission plans as the vehicle had them: start time, waypoints, cruise speed.
    missions: list[dict[str, object]] = field(default_factory=list)

    @property
    def duration_s(self) -> float:
        return float(self.truth["t_s"].iloc[-1])


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


class _Dive:
    """Mutable state of one simulation run."""

    def __init__(self, scenario: Scenario, profile: Profile, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.scenario, self.profile, self.fault = scenario, profile, scenario.fault
        self.vehicle = TwinThrusterVehicle(VehicleParams())
        self.rng = rng
        self.flow_noise = _Noise(rng, FLOW_NOISE_MPS)
        self.gyro_noise = _Noise(rng, GYRO_NOISE_RPS)
        self.force_noise = _Noise(rng, 0.25)
        self.torque_noise = _Noise(rng, 0.03)
        self.disturbance = [0.0, 0.0]
        self.tick = 0
        self.command = (0.0, 0.0)
        self.last_flow = 0.0
        self.last_gyro = 0.0
        self.out = SimulatedDive(scenario, seed, Stream(), Stream(), Stream(), [], [],
                                 pd.DataFrame())
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

    def advance(self, controller: PathFollower | None, dms_levels: tuple[float, ...] | None
                ) -> None:
        """One physics tick, publishing whatever is due at this instant."""
        t = self.time_s
        if self.tick % CONTROL_EVERY == 0:
            if controller is not None:
                self.command = controller.step(self.last_flow, self.last_gyro,
                                               CONTROL_EVERY * PHYSICS_DT_S)
            elif dms_levels is not None:
                self.command = (dms_levels[0], dms_levels[1])
            self.out.commands.add(t + self.jitter(), *self.command)
            s = self.vehicle.state
            self.truth_rows.append((t, s.surge_mps, s.yaw_rate_rps, s.heading_rad, s.x_m,
                                    s.y_m, s.thrust_n[0], s.thrust_n[1],
                                    self.last_flow, self.last_gyro))
        state = self.vehicle.state
        if self.tick % FLOW_EVERY == FLOW_EVERY // 2:
            reading = state.surge_mps + self.flow_noise.draw()
            self.last_flow = _quantise(self.sensor("flow_sensor", reading), FLOW_QUANTUM_MPS)
            self.out.flow.add(t + self.jitter(), self.last_flow)
        if self.tick % IMU_EVERY == 1:
            reading = state.yaw_rate_rps + self.gyro_noise.draw()
            self.last_gyro = _quantise(self.sensor("yaw_rate_sensor", reading),
                                       GYRO_QUANTUM_RPS)
            self.out.imu.add(t + self.jitter(), self.last_gyro)
        if self.fault is not None:
            self.vehicle.thruster_gain = [self.fault.thruster_gain(i, t) for i in (0, 1)]
        # Slow, small Ornstein-Uhlenbeck disturbance: the tank is steady, not perfectly still.
        decay = PHYSICS_DT_S / 2.0
        self.disturbance[0] += -decay * self.disturbance[0] + 0.1 * self.force_noise.draw()
        self.disturbance[1] += -decay * self.disturbance[1] + 0.1 * self.torque_noise.draw()
        self.vehicle.step(self.command, PHYSICS_DT_S, (self.disturbance[0], self.disturbance[1]))
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
            levels = tuple(float(v) for v in self.rng.uniform(-1.0, 1.0, 2))
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
        gains = ControllerGains(cruise_speed_mps=spec.cruise_speed_mps)
        controller = PathFollower(waypoints, gains)
        self.out.missions.append({"start_s": round(self.time_s, 6), "waypoints": waypoints,
                                  "cruise_speed_mps": spec.cruise_speed_mps})
        # The controller's navigation starts where the vehicle is, in its own frame.
        controller.heading = 0.0
        start = self.time_s
        settle_ticks = round(SETTLE_AFTER_MISSION_S / PHYSICS_DT_S)
        while settle_ticks > 0 and self.time_s - start < spec.max_duration_s:
            if self.fault_over():
                return
            self.advance(controller, None)
            if controller.finished:
                settle_ticks -= 1

    def finish(self) -> SimulatedDive:
        self.out.truth = pd.DataFrame(self.truth_rows, columns=[
            "t_s", "surge_mps", "yaw_rate_rps", "heading_rad", "x_m", "y_m",
            "thrust_0_n", "thrust_1_n", "flow_reading_mps", "yaw_rate_reading_rps"])
        return self.out


def simulate(scenario: Scenario, profile: Profile, seed: int = 0,
             start_ns: int = LOG_EPOCH_NS) -> SimulatedDive:
    """Fly ``scenario`` once; ``seed`` fixes every noise draw; the log's clock starts at
    ``start_ns`` (Unix time)."""
    missing = [p.name for p in scenario.phases
               if p.mission is None and p.excitation is None and p.name not in profile.dms]
    if missing:
        raise KeyError(f"profile {profile.name!r} defines no DMS {', '.join(missing)}")
    dive = _Dive(scenario, profile, seed)
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

