"""The text of a profile `auvdiag init-profile` drafts: each proposed signal with what the
user must check, the tables a profile needs, and where each signal lives in the log."""

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adapters.signals import (
    CLOCK_REFERENCE,
    MOOS_VALUE,
    OPERATING,
    OTHER_VALUES,
    FieldSource,
    TimeColumn,
)

# A controller's set point (mavros nav_info `commanded`, ArduPilot ATT `DesRoll`, `des_x`):
# it drives a model of the closed loop, but it is no actuator.
SET_POINT_NAME = re.compile(r"(commanded|desired|^des|setpoint|set_point|target)",
                            re.IGNORECASE)
BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
NEUTRAL = 1e-3            # a command this small is at rest


def typical_level(value: np.ndarray) -> float:
    """A command's median magnitude where it is not at rest."""
    moving = np.abs(value[np.isfinite(value) & (np.abs(value) > NEUTRAL)])
    return float(np.median(moving)) if moving.size else 0.0


@dataclass(frozen=True)
class Proposal:
    name: str
    source: FieldSource
    unit: str
    check: str            # what the user must check
    full_scale: float = 1.0
    level: float = 0.0    # a command's median magnitude where it is not neutral
    two_way: bool = False  # a command that also runs negative (a thruster that reverses)
    set_point: bool = False  # a controller's set point, whatever its name
    kind: str | None = None  # an actuator's kind where the log says it (a copter's motor)


@dataclass(frozen=True)
class DraftGroup:
    """An ``[[effort]]`` group the draft proposes."""

    members: list[str]
    name: str | None = None     # None: "group_N", guessed from the commands' levels
    said: str = ""              # what the log said of it, where it did


def is_set_point(proposal: Proposal) -> bool:
    return proposal.set_point or bool(
        SET_POINT_NAME.search(proposal.source.field.rsplit(".", 1)[-1]))


def signal_name(topic: str, field: str) -> str:
    """A signal's name from its field's (or, for a topic's own value, the topic's)."""
    text = re.sub(r"[^A-Za-z0-9]+", "_", f"{field}" if field != topic else topic).strip("_")
    return text.lower() or "signal"


def quoted(text: str) -> str:
    """``text`` as a TOML basic string: a log's names may hold quotes, backslashes or
    control characters (JSON's escapes are TOML's; TOML also refuses a raw DEL)."""
    return json.dumps(text).replace("\x7f", "\\u007f")


def toml_key(text: str) -> str:
    """``text`` as a TOML key: bare where TOML allows it."""
    return text if BARE_KEY.fullmatch(text) else quoted(text)


def entry(source: FieldSource, family: str) -> str:
    key = "column" if family == "csv" else "message" if family in ("mavlink", "dataflash",
                                                                    "ulog") \
        else "variable" if family == "moos" else "topic"
    # A CSV column is its own field; a MOOS variable's posting is its field `value`.
    bare = family == "csv" or (family == "moos" and source.field == MOOS_VALUE)
    parts = [f"{key} = {quoted(source.topic)}"] if bare else [
        f"{key} = {quoted(source.topic)}", f"field = {quoted(source.field)}"]
    if source.angle:
        parts[1:] = ["quaternion = [" + ", ".join(map(quoted, source.quaternion)) + "]",
                     f"angle = {quoted(source.angle)}"]
    if source.scale != 1.0:
        parts.append(f"scale = {source.scale:g}")
    if source.offset:
        parts.append(f"offset = {source.offset:g}")
    if source.where:
        parts.append("where = { " + ", ".join(f"{toml_key(k)} = {quoted(str(v))}"
                                             for k, v in source.where) + " }")
    if source.bits:
        parts.append(f"bits = {source.bits}")
    if source.changes_only:
        parts.append("changes_only = true")
    if source.mapped:
        meanings = [(str(raw), meaning) for raw, meaning in source.values]
        if source.otherwise is not None:
            meanings.append((OTHER_VALUES, source.otherwise))
        parts.append("values = { " + ", ".join(f"{toml_key(raw)} = {meaning:g}"
                                               for raw, meaning in meanings) + " }")
    return "{ " + ", ".join(parts) + " }"


def _groups_and_loops(groups: list[DraftGroup], loops: Sequence[tuple[str, str, str]]
                      ) -> list[str]:
    """The drafted ``[[effort]]`` groups and ``[[tracking]]`` loops, each with what to check."""
    lines: list[str] = []
    for number, group in enumerate(groups, 1):
        lines += ([f"# {group.said}: each one's share of their effort is judged."]
                  if group.said else
                  ["# CHECK: actuators that seem to act alike (their commands run at similar "
                   "levels and move", "# together in this log): each one's share of their "
                   "effort is judged. Split the group", "# as the frame's geometry says "
                   "(horizontal and vertical thrusters apart), add the mixing", "# factors."])
        lines += ["[[effort]]", f'name = "{group.name or f"group_{number}"}"',
                  "actuators = [" + ", ".join(f'"{m}"' for m in group.members) + "]", ""]
    for set_point, measured, rate in loops:
        lines += ["# A loop of the controller: how much rate its error brings, judged against "
                  "the log's own", "# beginning (a part that fails makes it slower). CHECK: "
                  "name the parts that make the rate.", "[[tracking]]",
                  f'name = "{measured}_loop"', f'set_point = "{set_point}"',
                  f'measured = "{measured}"', f'rate = "{rate}"',
                  '# moved_by = ["..."]   # CHECK: the actuators that make the rate', ""]
    return lines


def _header(path: Path, name: str, vehicle_said: str) -> list[str]:
    said = f": {vehicle_said}" if vehicle_said else ""
    return [f"# Starting profile written by `auvdiag init-profile` from {path.name}.",
            "# Every signal below is in that log and varies there. Lines marked CHECK are",
            "# what the log cannot tell: read them before you train.", "",
            "[vehicle]", f"name = {quoted(name)}",
            f"description = {quoted(f'drafted from {path.name}{said}')}",
            "dt_s = 0.1            # CHECK: the model step; not below the command rate", ""]


def render_draft(path: Path, name: str, family: str, commands: list[Proposal],
                 sensors: list[Proposal], operating: FieldSource | None,
                 time: TimeColumn | None, groups: list[DraftGroup],
                 loops: Sequence[tuple[str, str, str]] = (),
                 clock_reference: FieldSource | None = None, vehicle_said: str = "") -> str:
    """``vehicle_said``: what the log says of the vehicle that wrote it (its firmware)."""
    lines = _header(path, name, vehicle_said)
    # With set points in the log, the model follows the closed loop: driven by the set
    # points, the actuators read for the effort check only.
    closed_loop = any(is_set_point(p) for p in commands)
    if closed_loop:
        lines += ["# The log holds the controller's set points: they drive the model (how the "
                  "vehicle follows", "# them is what a model predicts best), and the "
                  "actuator outputs are [[outputs]], read", "# for the effort check only. "
                  "CHECK: move an output to [[commands]] to drive the model by it.", ""]
    for proposal in commands:
        kind = ('kind = "set_point"   # CHECK: a controller\'s set point (drives a model of '
                'the closed loop; no actuator)' if is_set_point(proposal) else
                f'kind = "{proposal.kind}"   # as the log says: {proposal.check}'
                if proposal.kind else
                'kind = "thruster"   # CHECK: thruster, rotor, control_surface or engine' + (
                    "" if closed_loop else " (or set_point)"))
        table = "[[outputs]]" if closed_loop and not is_set_point(proposal) else "[[commands]]"
        lines += [table, f'name = "{proposal.name}"',
                  f'component = "{proposal.name}"   # CHECK: the part that fails', kind,
                  f"description = {quoted(f'{proposal.source.topic} {proposal.source.said}')}",
                  ""]
    for proposal in sensors:
        lines += ["[[sensors]]", f'name = "{proposal.name}"',
                  f'component = "{proposal.name}_sensor"   # CHECK: the part that fails',
                  f'unit = "{proposal.unit}"   # CHECK: {proposal.check}',
                  f"full_scale = {proposal.full_scale:g}   # CHECK: twice the log's 99th "
                  "percentile",
                  f"description = {quoted(f'{proposal.source.topic} {proposal.source.said}')}",
                  ""]
    lines += _groups_and_loops(groups, loops)
    names = [p.name for p in sensors]
    lines += ["[matching]", "window_samples = 20", "decision_window_s = 3.0",
              'horizon_s = "auto"   # train chooses how long the model predicts unaided', "",
              "# CHECK: the paper's mission threshold: calibrate on normal logs",
              "[thresholds.mission]", *(f"{n} = 15.0" for n in names), "",
              "# CHECK: only 'nothing' is known; name the components each b vector means",
              "[[pattern]]", "case = 0",
              "b = { " + ", ".join(f"{n} = 0" for n in names) + " }", "components = []", "",
              f"[sources.{family}]"]
    if time is not None:
        lines.append(f'time = {{ column = {quoted(time.column)}, unit = "{time.unit}" }}'
                     "   # CHECK: the clock's unit")
    if operating is not None:
        lines.append(f"{OPERATING} = {entry(operating, family)}   # armed flag")
    if clock_reference is not None:
        lines.append(f"{CLOCK_REFERENCE} = {entry(clock_reference, family)}   # a UTC time "
                     "it carries: dates a log whose own clock is off")
    lines += ["", f"[sources.{family}.signals]"]
    for proposal in commands:
        lines.append(f"{proposal.name} = {entry(proposal.source, family)}   "
                     f"# CHECK: {proposal.check}")
    for proposal in sensors:
        lines.append(f"{proposal.name} = {entry(proposal.source, family)}")
    return "\n".join(lines) + "\n"
