"""What a draft calls a log's fields, and what their names say: PX4's fields by PX4's
vocabulary (`px4_names`), mavros's output channels as ArduPilot numbers its outputs, any
other by its own name."""

import re

from adapters.signals import FieldSource
from auvdiag_cli.jobs.draft_text import signal_name
from auvdiag_cli.jobs.px4_names import px4_name

# mavros's rc/out (SERVO_OUTPUT_RAW): `channels[0]` in a bag, `channels0` as `rostopic echo
# -p` flattens it, is the autopilot's output 1.
RC_OUT_CHANNEL = re.compile(r"channels\[?(\d+)\]?")


def draft_name(source: FieldSource, called: str, family: str) -> str:
    """``called``: what the field is called (`moos_draft.label`)."""
    channel = RC_OUT_CHANNEL.fullmatch(source.field) if family == "ros" and \
        source.topic.endswith("rc/out") else None
    return (family == "ulog" and px4_name(source)) or (
        channel is not None and f"servo{int(channel.group(1)) + 1}") or signal_name(
        source.topic, called)


def described(topic: str, named: str, family: str) -> str:
    """What a field's name says: a PX4 topic's fields (``xyz[2]``) say it with the topic's
    (``vehicle_angular_velocity``) and the name the draft gives it (`px4_name`)."""
    if family != "ulog":
        return named
    return " ".join(filter(None, (f"{topic}.{named}", px4_name(FieldSource(topic, named)))))
