"""What a drafted profile calls PX4's ULog fields: PX4 logs its measurements as arrays and
frames (`vehicle_angular_velocity` `xyz[2]`, `vehicle_local_position` `vz`), whose paths say
little in a report ("xyz_2 exceeded its threshold")."""

import re

from adapters.signals import FieldSource

PX4_NAMES = {
    ("vehicle_angular_velocity", "xyz[0]"): "roll_rate",     # FRD body rates, rad/s
    ("vehicle_angular_velocity", "xyz[1]"): "pitch_rate",
    ("vehicle_angular_velocity", "xyz[2]"): "yaw_rate",
    ("vehicle_local_position", "vx"): "north_speed",         # NED, m/s
    ("vehicle_local_position", "vy"): "east_speed",
    ("vehicle_local_position", "vz"): "heave",               # down positive, as a depth rate
    ("tecs_status", "height_rate"): "height_rate",           # up positive
    ("tecs_status", "true_airspeed_filtered"): "airspeed",
    ("airspeed", "true_airspeed_m_s"): "airspeed",
}
# PX4 numbers its motors and servos from 1 (the CA_ parameters, the mixer's outputs); the
# logged arrays count from 0.
NUMBERED_OUTPUTS = {"actuator_motors": "motor", "actuator_servos": "servo"}
ELEMENT = re.compile(r"control\[(\d+)\]")


def px4_name(source: FieldSource) -> str | None:
    """The draft's name for a PX4 field; None where PX4's own path is the best there is."""
    named = PX4_NAMES.get((source.topic, source.field))
    element = ELEMENT.fullmatch(source.field)
    if named is None and element is not None and source.topic in NUMBERED_OUTPUTS:
        named = f"{NUMBERED_OUTPUTS[source.topic]}_{int(element.group(1)) + 1}"
    return named
