"""Attitude angles a draft reads from logged quaternions: PX4 and mavros log the attitude,
and the attitude their controller targets, as quaternions only. Roll and pitch are drafted
(yaw wraps at ±π, which no model of the motion follows); with ``--closed-loop`` the target
drives the model beside the attitude, and each angle's loop with its rate is drafted for
the change test's gain (`[[tracking]]`)."""

from dataclasses import dataclass

import numpy as np

from adapters import LogInventory
from adapters.signals import FieldSource
from auvdiag_cli.jobs.autopilot_set_points import MAVROS_SP, first_instance, namespace_of
from auvdiag_cli.jobs.draft_text import Proposal

DRAFTED_ANGLES = ("roll", "pitch")
SET_POINT_SUFFIX = "_set_point"


@dataclass(frozen=True)
class Attitudes:
    """Where a family logs its attitude and its controller's target, each (topic, the
    quaternion's path), and the drafted names of the rates the angles' loops make."""

    measured: tuple[str, str]
    target: tuple[str, str]
    rates: tuple[str, str]            # roll's, pitch's
    array: bool                       # q[0..3], w first (PX4); else .w .x .y .z (ROS)

    def paths(self, quaternion: str) -> tuple[str, ...]:
        if self.array:
            return tuple(f"{quaternion}[{i}]" for i in range(4))
        return tuple(f"{quaternion}.{part}" for part in "wxyz")


ATTITUDES = {
    # PX4: FRD body to NED; roll right wing down, pitch nose up positive.
    "ulog": Attitudes(("vehicle_attitude", "q"), ("vehicle_attitude_setpoint", "q_d"),
                      ("roll_rate", "pitch_rate"), array=True),
    # mavros: FLU body to ENU (REP 103); pitch is nose down positive there.
    "ros": Attitudes(("/mavros/imu/data", "orientation"),
                     (f"{MAVROS_SP}target_attitude", "orientation"),
                     ("angular_velocity_x", "angular_velocity_y"), array=False),
}


def attitude_candidates(contents: LogInventory, family: str, closed_loop: bool
                        ) -> list[tuple[str, FieldSource]]:
    """("sensor", roll and pitch) of the attitude the log holds, and with ``closed_loop``
    ("set_point", …) of the attitude its controller targets where both are logged (a ROS
    log's under any one namespace)."""
    where = ATTITUDES.get(family)
    if where is None:
        return []
    topics = {topic.name: topic for topic in contents.topics}
    found: list[tuple[str, FieldSource]] = []
    for prefix in {namespace_of(name, where.measured[0], family) for name in topics} - {None}:
        ends = [("sensor", where.measured)]
        if closed_loop:
            ends.append(("set_point", where.target))
        for kind, (topic_name, quaternion) in ends:
            topic, paths = topics.get(f"{prefix}{topic_name}"), where.paths(quaternion)
            if topic is None or not set(paths) <= set(topic.fields):
                break
            found += [(kind, FieldSource(topic.name, paths[0], where=first_instance(topic),
                                         quaternion=paths, angle=angle))
                      for angle in DRAFTED_ANGLES]
    return found


def angle_proposal(source: FieldSource, series: np.ndarray, family: str) -> Proposal:
    """The drafted angle: the controller's target as a set point, the attitude a sensor."""
    target = ATTITUDES[family].target[0]
    if namespace_of(source.topic, target, family) is not None:
        return Proposal(source.angle + SET_POINT_SUFFIX, source, "rad",
                        "the attitude the controller targets, from its quaternion",
                        set_point=True)
    full_scale = float(np.nanpercentile(np.abs(series), 99)) * 2
    frames = "FRD to NED" if ATTITUDES[family].array else "FLU to ENU: pitch nose down positive"
    return Proposal(source.angle, source, "rad", f"from its quaternion ({frames})",
                    round(full_scale, 2) or 1.0)


def angle_loops(names: set[str], family: str) -> list[tuple[str, str, str]]:
    """(set point, measured, rate) of each angle's loop the draft holds whole."""
    rates = ATTITUDES[family].rates if family in ATTITUDES else ()
    return [(angle + SET_POINT_SUFFIX, angle, rate)
            for angle, rate in zip(DRAFTED_ANGLES, rates, strict=False)
            if {angle + SET_POINT_SUFFIX, angle, rate} <= names]
