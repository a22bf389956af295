"""The operating flag `init-profile` proposes: when the vehicle that wrote the log was armed
(or, under MOOS-IvP, driven by its helm), in the form its family logs it. Disarmed time
(on deck, carried, idle in the water) is then neither trained on nor judged."""

from collections.abc import Callable

import numpy as np

from adapters import LogInventory
from adapters.signals import FieldSource
from auvdiag_cli.jobs.moos_draft import operating as moos_operating

MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID = 6, 8
# mavros's vehicle state (`mavros_msgs/State`): its `armed` flag.
MAVROS_STATE, MAVROS_ARMED = "mavros/state", "armed"
# PX4's armed state (ULog `actuator_armed`): its `armed` flag, a bool.
PX4_ARMED = FieldSource("actuator_armed", "armed", bits=1)
# Reads sources on the log: what each reads (a source the log does not fill reads nothing).
Reader = Callable[[dict[str, FieldSource]], dict[str, np.ndarray]]


def draft_operating(family: str, contents: LogInventory, read: Reader) -> FieldSource | None:
    """The armed flag where the log has one (ArduPilot's ARM records or heartbeat, mavros's
    state, PX4's actuator_armed), or MOOS-IvP's helm driving; None where it has none."""
    names = {topic.name for topic in contents.topics}
    if family == "dataflash" and "ARM" in names:
        return FieldSource("ARM", "ArmState", changes_only=True)
    if family == "moos":
        return moos_operating(names)
    if family == "ulog":
        return PX4_ARMED if PX4_ARMED.topic in names else None
    if family == "ros":
        return next((FieldSource(topic.name, MAVROS_ARMED) for topic in contents.topics
                     if topic.name.rstrip("/").endswith(MAVROS_STATE)
                     and MAVROS_ARMED in topic.fields), None)
    if family != "mavlink" or "HEARTBEAT" not in names:
        return None
    return _heartbeat_armed(read)


def _heartbeat_armed(read: Reader) -> FieldSource | None:
    """The armed bit of the autopilot's own heartbeats: not the ground station's, nor those
    of companions and cameras, which say MAV_AUTOPILOT_INVALID."""
    found = read({"type": FieldSource("HEARTBEAT", "type"),
                  "autopilot": FieldSource("HEARTBEAT", "autopilot")})
    if "type" not in found or "autopilot" not in found:
        return None
    vehicle = [int(t) for t, a in zip(found["type"], found["autopilot"], strict=True)
               if int(t) != MAV_TYPE_GCS and int(a) != MAV_AUTOPILOT_INVALID]
    if not vehicle:
        return None
    kind = max(set(vehicle), key=vehicle.count)
    return FieldSource("HEARTBEAT", "base_mode", where=(("type", str(kind)),), bits=128)
