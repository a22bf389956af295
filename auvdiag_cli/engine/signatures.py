"""Derive the pattern table from the model: simulate each single-component fault (a sensor
reading zero, a thruster producing nothing) with the dynamics model as the vehicle, on each
DMS and on a mission, and read the b signatures the diagnosis would see. The signatures on
the mission give the table; those on the DMSs show which sequence separates which
candidates (what active diagnosis relies on).

The mission is flown by the profile's controller when it describes one (closed loop: the
controller answers the fault). Without one, any vehicle's table comes open loop: the
commands of a normal log of the vehicle are replayed as they were, the fault acting from
FAULT_AT_S into them, or, without a log, the profile's DMSs one after another."""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.resample import AlignedFrame
from auvdiag_cli.engine.segments import dms_template
from auvdiag_cli.vehicle.controller import VehicleController
from auvdiag_cli.vehicle.followers import make_follower
from auvdiag_cli.vehicle.profile import MISSION_MODE, PatternRow, Profile
from auvdiag_errors import DerivationError
from models.fast import FastStepper, fast_replay
from models.store import LoadedModel

FAULT_AT_S = 20.0          # into the mission: after the first leg has begun
MISSION_S = 90.0
PAPER_RECTANGLE = [(4.0, 0.0), (4.0, 2.0), (0.0, 2.0), (0.0, 0.0)]


@dataclass(frozen=True)
class Signature:
    component: str
    b: dict[str, dict[str, int]]      # mode (ZA, …, mission) -> signal -> bit


@dataclass(frozen=True)
class DerivedTable:
    signatures: list[Signature]
    rows: list[PatternRow]            # grouped by the mission signature
    matches_profile: bool
    unseen_on_mission: tuple[str, ...] = ()


def _bits(measured: np.ndarray, modelled: np.ndarray, profile: Profile, mode: str,
          model: LoadedModel) -> dict[str, int]:
    """The b a fault gives on ``mode`` under the profile's own thresholds for it (the
    table describes the vehicle, not one model's calibration)."""
    return Judging.of(model, profile).decided_b(measured, modelled,
                                                profile.thresholds_for(mode))


def _faults(profile: Profile) -> list[tuple[str, int | None, int | None]]:
    """(component, actuator index, sensor index) of every single-component fault."""
    faults: list[tuple[str, int | None, int | None]] = [
        (c.component, i, None) for i, c in enumerate(profile.commands)]
    return faults + [(s.component, None, j) for j, s in enumerate(profile.sensors)]


def dms_signature(model: LoadedModel, profile: Profile, dms_name: str, component: str
                  ) -> dict[str, int]:
    """The b the model predicts on a DMS when ``component`` has failed outright."""
    fault = next(f for f in _faults(profile) if f[0] == component)
    return _on_dms(model, profile, dms_name, fault[1], fault[2])


@dataclass(frozen=True)
class OpenLoop:
    """A command history the fault is replayed on as it is (no controller answers)."""

    commands: np.ndarray
    start: np.ndarray          # the state it starts from
    fault_step: int = 0
    inputs: np.ndarray | None = None   # measured inputs (None: each at its typical value)


def _on_dms(model: LoadedModel, profile: Profile, name: str, actuator: int | None,
            sensor: int | None) -> dict[str, int]:
    history = OpenLoop(dms_template(profile.dms[name], profile.dt_s),
                       np.zeros(len(profile.sensors)))
    return _open_loop(model, profile, name, history, actuator, sensor)


def _open_loop(model: LoadedModel, profile: Profile, mode: str, history: OpenLoop,
               actuator: int | None, sensor: int | None) -> dict[str, int]:
    modelled = fast_replay(model.dynamics, model.normaliser,
                           model.drive(history.commands, history.inputs), history.start)
    executed = history.commands.copy()
    if actuator is not None:
        executed[history.fault_step:, actuator] = 0.0
    measured = fast_replay(model.dynamics, model.normaliser,
                           model.drive(executed, history.inputs), history.start)
    if sensor is not None:
        measured[history.fault_step:, sensor] = 0.0
    return _bits(measured, modelled, profile, mode, model)


def log_mission(frame: AlignedFrame, profile: Profile) -> OpenLoop:
    """The open-loop mission of a normal log: its longest stretch with every signal
    measured, from the robust state at its start."""
    from models.rollouts import robust_state
    from models.training import complete_stretches

    usable = np.where(np.isfinite(frame.drive).all(axis=1, keepdims=True), frame.sensors,
                      np.nan)
    stretches = complete_stretches(usable)
    if not stretches:
        raise DerivationError("the log has no stretch with every signal measured to replay")
    begin, end = max(stretches, key=lambda s: s[1] - s[0])
    return open_loop_mission(profile, frame.commands[begin:end],
                             robust_state(frame.sensors, begin, begin, end),
                             frame.inputs[begin:end] if frame.input_names else None)


def open_loop_mission(profile: Profile, commands: np.ndarray | None = None,
                      start: np.ndarray | None = None, inputs: np.ndarray | None = None
                      ) -> OpenLoop:
    """The open-loop mission: a log's commands (from its state ``start``), or the DMSs one
    after another from rest."""
    if commands is None:
        if not profile.dms:
            raise DerivationError(f"profile {profile.name!r} describes neither a [controller] nor "
                             "DMSs: give a normal log of the vehicle (--log) whose commands "
                             "the faults are replayed on")
        commands = np.vstack([dms_template(d, profile.dt_s) for d in profile.dms.values()])
    if start is None:
        start = np.zeros(len(profile.sensors))
    fault_step = min(round(FAULT_AT_S / profile.dt_s), len(commands) // 4)
    return OpenLoop(commands, start, fault_step, inputs)


def _on_mission(model: LoadedModel, profile: Profile, waypoints: list[tuple[float, float]],
                actuator: int | None, sensor: int | None) -> dict[str, int]:
    spec = profile.controller
    assert spec is not None
    depths = profile.simulation.mission_depths_m if profile.simulation else ()
    controller = make_follower(spec, waypoints, spec.gains,
                               [depths[i % len(depths)] for i in range(len(waypoints))]
                               if depths else [])
    plant = FastStepper(model.dynamics, model.normaliser)
    plant.warm_up(model.drive(np.empty((0, len(profile.command_names)))),
                  np.zeros(len(profile.sensor_names)))
    vehicle = VehicleController(spec, profile.sensor_names, profile.command_names, controller)
    fault_step = round(FAULT_AT_S / profile.dt_s)
    readings, commands = [], []
    for step in range(round(MISSION_S / profile.dt_s)):
        reading = plant.current.copy()
        if sensor is not None and step >= fault_step:
            reading[sensor] = 0.0
        readings.append(reading)
        command = vehicle.step(reading, profile.dt_s)
        commands.append(command)
        executed = command.copy()
        if actuator is not None and step >= fault_step:
            executed[actuator] = 0.0
        plant.step(model.drive(executed[None, :])[0])
    modelled = fast_replay(model.dynamics, model.normaliser, model.drive(np.asarray(commands)),
                           readings[0])
    return _bits(np.asarray(readings), modelled, profile, MISSION_MODE, model)


def derive_table(model: LoadedModel, profile: Profile,
                 waypoints: list[tuple[float, float]] | None = None,
                 open_loop: OpenLoop | None = None,
                 progress: Callable[[str], None] = lambda _: None) -> DerivedTable:
    """``open_loop``: the mission to replay the faults on without a controller; by default
    the profile's controller flies the paper's rectangle, or, without one, the DMSs are
    played one after another."""
    if open_loop is None and profile.controller is None:
        open_loop = open_loop_mission(profile)
    signatures = []
    for component, actuator, sensor in _faults(profile):
        progress(f"simulating {component} failed")
        bits = {name: _on_dms(model, profile, name, actuator, sensor) for name in profile.dms}
        bits[MISSION_MODE] = (
            _open_loop(model, profile, MISSION_MODE, open_loop, actuator, sensor)
            if open_loop is not None else
            _on_mission(model, profile, waypoints or PAPER_RECTANGLE, actuator, sensor))
        signatures.append(Signature(component, bits))
    groups: dict[tuple[int, ...], list[str]] = {}
    for signature in signatures:
        key = tuple(signature.b[MISSION_MODE][n] for n in profile.sensor_names)
        groups.setdefault(key, []).append(signature.component)
    # A failure the mission never shows is no row of the table (the DMS columns show where
    # it can be seen); the all-zero row stays "nothing".
    quiet = tuple(0 for _ in profile.sensor_names)
    unseen = tuple(groups.pop(quiet, []))
    groups[quiet] = []
    rows = []
    next_case = max((r.case for r in profile.pattern), default=-1) + 1   # for rows not in it
    for key, components in sorted(groups.items(), key=lambda item: (sum(item[0]) > 0,
                                                                    -sum(item[0]), item[0])):
        existing = next((r for r in profile.pattern
                         if tuple(r.b[n] for n in profile.sensor_names) == key), None)
        if existing is not None:
            case = existing.case
        else:
            case, next_case = next_case, next_case + 1
        rows.append(PatternRow(case, dict(zip(profile.sensor_names, key, strict=True)),
                               tuple(components)))
    wanted = {(tuple(r.b.values()), tuple(sorted(r.components))) for r in profile.pattern}
    derived = {(tuple(r.b.values()), tuple(sorted(r.components))) for r in rows}
    return DerivedTable(signatures, sorted(rows, key=lambda r: r.case), wanted == derived,
                        unseen)
