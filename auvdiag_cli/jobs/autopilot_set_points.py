"""ArduPilot's set points as a drafted model of the closed loop: each set point its
controller logs beside what it measured, and the attitude loops whose gain the change
test judges."""

from dataclasses import replace

from adapters import LogInventory
from adapters.signals import FieldSource
from auvdiag_cli.jobs.draft_text import Proposal

DEGREES = 0.017453292519943295
# ArduPilot's controllers log each set point beside what they measured (Copter and Sub:
# ATT in degrees, RATE in deg/s, CTUN's climb rates in cm/s): message -> (set point,
# measured, scale to SI, unit). The climb rates are negated like a drafted climb (down
# positive, as a depth rate).
ARDUPILOT_SET_POINTS = {
    "ATT": (("DesRoll", "Roll", DEGREES, "rad"), ("DesPitch", "Pitch", DEGREES, "rad")),
    "RATE": (("RDes", "R", DEGREES, "rad/s"), ("PDes", "P", DEGREES, "rad/s"),
             ("YDes", "Y", DEGREES, "rad/s")),
    "CTUN": (("DCRt", "CRt", -0.01, "m/s"),),
}
# The attitude loops whose gain the change test can judge (`[[tracking]]`): set point ->
# (what was measured beside it, its rate), each (message, field).
ARDUPILOT_LOOPS = {("ATT", "DesRoll"): (("ATT", "Roll"), ("RATE", "R")),
                   ("ATT", "DesPitch"): (("ATT", "Pitch"), ("RATE", "P"))}


def set_point_pairs(contents: LogInventory) -> list[tuple[str, FieldSource]]:
    """("set_point", source) and ("sensor", source) of each ArduPilot set point the log
    holds beside what was measured (`ARDUPILOT_SET_POINTS`)."""
    found: list[tuple[str, FieldSource]] = []
    for topic in contents.topics:
        for desired, measured, _, _ in ARDUPILOT_SET_POINTS.get(topic.name, ()):
            if {desired, measured} <= set(topic.fields):
                found += [("set_point", FieldSource(topic.name, desired)),
                          ("sensor", FieldSource(topic.name, measured))]
    return found


def paired_unit(source: FieldSource) -> tuple[float, str] | None:
    """The scale to SI and the unit of an ArduPilot set point or what was measured beside
    it; None for any other field."""
    return next(((scale, unit) for desired, measured, scale, unit
                 in ARDUPILOT_SET_POINTS.get(source.topic, ())
                 if source.field in (desired, measured)), None)


def set_point_proposal(name: str, source: FieldSource, scale: float, unit: str) -> Proposal:
    return Proposal(name, replace(source, scale=scale), unit, "the controller's set point, "
                    "in the unit of what it measured beside it", set_point=True)


def attitude_loops(commands: list[Proposal], sensors: list[Proposal]) -> list[tuple[str, str, str]]:
    """(set point, measured, rate) of each ArduPilot attitude loop the draft holds whole."""
    named = {(p.source.topic, p.source.field): p.name for p in [*commands, *sensors]}
    return [(named[point], named[measured], named[rate])
            for point, (measured, rate) in ARDUPILOT_LOOPS.items()
            if {point, measured, rate} <= set(named)]
