"""Autopilots' set points as a drafted model of the closed loop: each set point a
controller logs beside what it measured (ArduPilot in one DataFlash message or two
telemetry messages, PX4 in two ULog topics, mavros in two ROS topics), and the attitude
loops whose gain the change test judges."""

from dataclasses import dataclass, replace

from adapters import LogInventory, TopicInfo
from adapters.signals import FieldSource
from auvdiag_cli.jobs.draft_text import Proposal, signal_name
from auvdiag_cli.jobs.px4_names import px4_name

DEGREES = 0.017453292519943295


@dataclass(frozen=True)
class SetPointPair:
    """A set point and what was measured beside it, each (topic, field), and each one's
    scale to the one SI unit they share."""

    set_point: tuple[str, str]
    measured: tuple[str, str]
    scale: float
    unit: str
    measured_scale: float | None = None     # None: the set point's

    def scale_of(self, end: tuple[str, str]) -> float:
        return self.scale if end == self.set_point or self.measured_scale is None \
            else self.measured_scale


def _ardupilot(message: str, desired: str, measured: str, scale: float, unit: str
               ) -> SetPointPair:
    return SetPointPair((message, desired), (message, measured), scale, unit)


def _px4(set_point: str, measured: str, pair: tuple[str, str], unit: str) -> SetPointPair:
    return SetPointPair((set_point, pair[0]), (measured, pair[1]), 1.0, unit)


RATES_SP, RATES = "vehicle_rates_setpoint", "vehicle_angular_velocity"
POSITION_SP, POSITION = "vehicle_local_position_setpoint", "vehicle_local_position"
MAVROS_SP = "/mavros/setpoint_raw/"
SET_POINT_PAIRS = {
    # ArduPilot's controllers (Copter, Sub, Plane's ATT and RATE): ATT in degrees, RATE in
    # deg/s, CTUN's climb rates in cm/s, negated like a drafted climb (down positive, as a
    # depth rate).
    "dataflash": (
        _ardupilot("ATT", "DesRoll", "Roll", DEGREES, "rad"),
        _ardupilot("ATT", "DesPitch", "Pitch", DEGREES, "rad"),
        _ardupilot("RATE", "RDes", "R", DEGREES, "rad/s"),
        _ardupilot("RATE", "PDes", "P", DEGREES, "rad/s"),
        _ardupilot("RATE", "YDes", "Y", DEGREES, "rad/s"),
        _ardupilot("CTUN", "DCRt", "CRt", -0.01, "m/s")),
    # ArduPilot's telemetry: the attitude its controller targets (NAV_CONTROLLER_OUTPUT, in
    # degrees; Copter, Sub and Plane stream it) beside the attitude (ATTITUDE, rad).
    "mavlink": (
        SetPointPair(("NAV_CONTROLLER_OUTPUT", "nav_roll"), ("ATTITUDE", "roll"), DEGREES,
                     "rad", 1.0),
        SetPointPair(("NAV_CONTROLLER_OUTPUT", "nav_pitch"), ("ATTITUDE", "pitch"), DEGREES,
                     "rad", 1.0)),
    # PX4 logs the rate controller's set point and the filtered gyro rates (FRD, rad/s), the
    # position controller's velocity set point and the estimate (NED, m/s: vz down
    # positive), and a fixed wing's TECS its height rate and airspeed. PX4 logs its
    # attitude as a quaternion only: no attitude angle to pair with its set point.
    "ulog": (
        _px4(RATES_SP, RATES, ("roll", "xyz[0]"), "rad/s"),
        _px4(RATES_SP, RATES, ("pitch", "xyz[1]"), "rad/s"),
        _px4(RATES_SP, RATES, ("yaw", "xyz[2]"), "rad/s"),
        _px4(POSITION_SP, POSITION, ("vx", "vx"), "m/s"),
        _px4(POSITION_SP, POSITION, ("vy", "vy"), "m/s"),
        _px4(POSITION_SP, POSITION, ("vz", "vz"), "m/s"),
        _px4("tecs_status", "tecs_status", ("height_rate_setpoint", "height_rate"), "m/s"),
        _px4("tecs_status", "tecs_status", ("true_airspeed_sp", "true_airspeed_filtered"),
             "m/s")),
    # mavros (under any namespace): the attitude controller's body-rate set point
    # (ATTITUDE_TARGET, as PX4 streams it) beside the IMU's rates, and the local velocity
    # set point beside the estimate's (both in mavros's ENU / FLU frames).
    "ros": tuple(SetPointPair((f"{MAVROS_SP}target_attitude", f"body_rate.{axis}"),
                              ("/mavros/imu/data", f"angular_velocity.{axis}"), 1.0, "rad/s")
                 for axis in "xyz") + tuple(
        SetPointPair((f"{MAVROS_SP}target_local", f"velocity.{axis}"),
                     ("/mavros/local_position/velocity_local", f"twist.linear.{axis}"), 1.0,
                     "m/s") for axis in "xyz"),
}
# The attitude loops whose gain the change test can judge (`[[tracking]]`): set point ->
# (what was measured beside it, its rate), each (message, field).
ARDUPILOT_LOOPS = {("ATT", "DesRoll"): (("ATT", "Roll"), ("RATE", "R")),
                   ("ATT", "DesPitch"): (("ATT", "Pitch"), ("RATE", "P")),
                   ("NAV_CONTROLLER_OUTPUT", "nav_roll"): (("ATTITUDE", "roll"),
                                                           ("ATTITUDE", "rollspeed")),
                   ("NAV_CONTROLLER_OUTPUT", "nav_pitch"): (("ATTITUDE", "pitch"),
                                                            ("ATTITUDE", "pitchspeed"))}


def first_instance(topic: TopicInfo) -> tuple[tuple[str, str], ...]:
    """The ``where`` that reads a topic logged by several instances from its first."""
    return tuple((key, values[0]) for key, values in topic.instances if len(values) > 1)


def set_point_pairs(contents: LogInventory, family: str) -> list[tuple[str, FieldSource]]:
    """("set_point", source) and ("sensor", source) of each set point the log holds beside
    what was measured (`SET_POINT_PAIRS`; a ROS log's under any one namespace)."""
    topics = {topic.name: topic for topic in contents.topics}
    found: list[tuple[str, FieldSource]] = []
    for pair in SET_POINT_PAIRS.get(family, ()):
        for prefix in {namespace_of(name, pair.set_point[0], family) for name in topics} - {None}:
            ends = [(kind, topics.get(f"{prefix}{topic}"), field) for kind, (topic, field)
                    in (("set_point", pair.set_point), ("sensor", pair.measured))]
            if all(topic is not None and field in topic.fields for _, topic, field in ends):
                found += [(kind, FieldSource(topic.name, field, where=first_instance(topic)))
                          for kind, topic, field in ends if topic is not None]
    return found


def namespace_of(name: str, topic: str, family: str) -> str | None:
    """What ``name`` holds before ``topic`` (a ROS namespace: "/uav1"), "" where it is
    ``topic``; None where it is another topic."""
    if name == topic:
        return ""
    if family == "ros" and name.endswith(topic) and name[:-len(topic)].startswith("/"):
        return name[:-len(topic)]
    return None


def pairing(source: FieldSource, family: str) -> tuple[float, str, str] | None:
    """The scale to SI, the unit and the drafted name of a set point or what was measured
    beside it; None for any other field."""
    for pair in SET_POINT_PAIRS.get(family, ()):
        for end in (pair.set_point, pair.measured):
            if source.field == end[1] and namespace_of(source.topic, end[0], family) is not None:
                return pair.scale_of(end), pair.unit, _pair_name(pair, end, family)
    return None


def _pair_name(pair: SetPointPair, end: tuple[str, str], family: str) -> str:
    """PX4's and mavros's named as what was measured, the set point with "_set_point"; a
    telemetry message's by its field (nav_roll, roll); a DataFlash message's by message and
    field (att_desroll: ATT and RATE both log a roll)."""
    measured = px4_name(FieldSource(*pair.measured)) if family == "ulog" else \
        signal_name("", pair.measured[1]) if family == "ros" else None
    if measured is not None:
        return measured + ("_set_point" if end == pair.set_point else "")
    return signal_name("", end[1] if family == "mavlink" else f"{end[0]}_{end[1]}")


def set_point_proposal(name: str, source: FieldSource, scale: float, unit: str) -> Proposal:
    return Proposal(name, replace(source, scale=scale), unit, "the controller's set point, "
                    "in the unit of what it measured beside it", set_point=True)


def attitude_loops(commands: list[Proposal], sensors: list[Proposal]) -> list[tuple[str, str, str]]:
    """(set point, measured, rate) of each ArduPilot attitude loop the draft holds whole
    (`ARDUPILOT_LOOPS`)."""
    named = {(p.source.topic, p.source.field): p.name for p in [*commands, *sensors]}
    return [(named[point], named[measured], named[rate])
            for point, (measured, rate) in ARDUPILOT_LOOPS.items()
            if {point, measured, rate} <= set(named)]
