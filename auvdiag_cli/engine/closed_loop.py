"""Substituting Control in closed loop: from the fault onset on, the vehicle's own controller
(described by the profile) is fed the model's signals instead of the failed sensor, and the
dynamics model stands in for the vehicle. The result is the commands it would have issued
and the path it would have followed, up to the end of the mission leg. A model driven by
measured inputs (battery voltage, attitude) has them held at their typical values: the
replay runs past what the log measured."""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.engine.histories import Histories
from auvdiag_cli.engine.missions import MissionLeg
from auvdiag_cli.vehicle.controller import ControllerSpec, VehicleController
from auvdiag_cli.vehicle.followers import make_follower
from models.fast import FastStepper
from models.rollouts import robust_state
from models.store import LoadedModel

SETTLE_AFTER_LAST_WAYPOINT_S = 5.0
MAX_REPLAY_S = 600.0


@dataclass
class ClosedLoopReplay:
    start_s: float
    reached: bool                    # the controller reached its last waypoint
    finished_s: float | None         # when, in log seconds
    miss_m: float                    # final position to the last waypoint
    last_waypoint: tuple[float, float]
    time_s: np.ndarray
    x_m: np.ndarray                  # path in the leg's navigation frame
    y_m: np.ndarray
    commands: np.ndarray


def _leg_at(legs: Sequence[MissionLeg], time_s: float) -> MissionLeg | None:
    started = [leg for leg in legs if leg.start_s <= time_s]
    return max(started, key=lambda leg: leg.start_s) if started else None


def replay_closed_loop(model: LoadedModel, spec: ControllerSpec, histories: Histories,
                       onset_s: float, legs: Sequence[MissionLeg], dt_s: float
                       ) -> ClosedLoopReplay | None:
    """None when no mission leg was under way at the onset (or nothing was replayed)."""
    leg = _leg_at(legs, onset_s)
    if leg is None or histories.matching is None:
        return None
    time_s, commands, measured = histories.time_s, histories.commands, histories.matching.measured
    sensor_names, command_names = histories.sensor_names, histories.command_names
    gains = spec.gains_for(leg.cruise_speed_mps)
    controller = make_follower(spec, list(leg.waypoints), gains, list(leg.depths_m))
    vehicle = VehicleController(spec, sensor_names, command_names, controller)
    first = int(np.searchsorted(time_s, leg.start_s))
    onset = int(np.searchsorted(time_s, onset_s))
    # Before the onset the sensors were sound: they bring the controller to its state then.
    for row in np.nan_to_num(measured[first:onset]):
        vehicle.step(row, dt_s)
    stepper = FastStepper(model.dynamics, model.normaliser)
    state = stepper.warm_up(model.drive(commands[first:onset]),
                           np.nan_to_num(robust_state(measured, first, first, onset + 1)))
    path, issued = [(controller.x, controller.y)], []
    settle = round(SETTLE_AFTER_LAST_WAYPOINT_S / dt_s)
    finished_step = None
    for step in range(round(MAX_REPLAY_S / dt_s)):
        command = vehicle.step(state, dt_s)
        issued.append(command)
        state = stepper.step(model.drive(command[None, :])[0])
        path.append((controller.x, controller.y))
        if controller.finished:
            finished_step = step if finished_step is None else finished_step
            settle -= 1
            if settle <= 0:
                break
    xy = np.asarray(path)
    last = leg.waypoints[-1]
    return ClosedLoopReplay(
        start_s=round(float(time_s[min(onset, len(time_s) - 1)]), 3),
        reached=finished_step is not None,
        finished_s=None if finished_step is None else round(onset_s + finished_step * dt_s, 1),
        miss_m=round(float(np.hypot(xy[-1, 0] - last[0], xy[-1, 1] - last[1])), 3),
        last_waypoint=last, time_s=onset_s + dt_s * np.arange(len(xy)), x_m=xy[:, 0],
        y_m=xy[:, 1], commands=np.asarray(issued))
