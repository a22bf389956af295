"""What `init-profile` knows of MOOS-IvP logs: a variable's own posting goes by the
variable's name, and pMarinePID's outputs are the vehicle's actuator commands, in the units
pMarinePID posts them (thrust in percent, rudder and elevator in degrees)."""

import math
import re

import numpy as np

from adapters.signals import MOOS_VALUE, FieldSource
from auvdiag_cli.jobs.draft_text import Proposal, typical_level

# MOOS-IvP's pMarinePID turns the helm's set points into these actuator commands.
PID_OUTPUT = re.compile(r"^DESIRED_(THRUST|RUDDER|ELEVATOR)")
THRUST_PERCENT = 0.01
# true while the vehicle is deployed, as the IvP tools post it.
MOOS_DEPLOY = "DEPLOY"
# The helm's own heartbeat: PARK, DRIVE, STANDBY, DISABLED (MALCONFIG where its mission file
# is wrong); only DRIVE is the helm driving (a deployed vehicle parks on an all-stop).
HELM_STATE = FieldSource("IVPHELM_STATE", MOOS_VALUE, values=(("DRIVE", 1.0),), otherwise=0.0)


def operating(variables: set[str]) -> FieldSource | None:
    """The helm driving, where the log has its state, else `DEPLOY`."""
    if HELM_STATE.topic in variables:
        return HELM_STATE
    return FieldSource(MOOS_DEPLOY, MOOS_VALUE) if MOOS_DEPLOY in variables else None


def label(topic: str, field: str, family: str) -> str:
    """What a field is called: a MOOS variable's own posting goes by the variable's name."""
    return topic if family == "moos" and field == MOOS_VALUE else field


def pid_output(source: FieldSource, series: np.ndarray) -> Proposal | None:
    """pMarinePID's output as a command of -1 … 1, or None where ``source`` is none."""
    found = PID_OUTPUT.match(label(source.topic, source.field, "moos"))
    if found is None:
        return None
    name = source.topic.lower()
    if found.group(1) == "THRUST":
        scaled = FieldSource(source.topic, source.field, THRUST_PERCENT, where=source.where)
        return Proposal(name, scaled, "1", "pMarinePID's thrust in percent, as a fraction",
                        level=typical_level(series * THRUST_PERCENT),
                        two_way=bool((series < 0).any()), kind="thruster")
    # Degrees; the surface's limit (pMarinePID's max_rudder, max_elevator) is the largest
    # deflection this log asked, to a whole degree.
    limit = float(math.ceil(np.nanmax(np.abs(series)))) or 1.0
    scaled = FieldSource(source.topic, source.field, 1.0 / limit, where=source.where)
    return Proposal(name, scaled, "1", f"pMarinePID's angle in degrees over {limit:g}, the "
                    "largest this log asks: set the surface's limit", two_way=True,
                    level=typical_level(series / limit), kind="control_surface")
