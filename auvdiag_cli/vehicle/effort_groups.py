"""``[[effort]]`` in a profile: actuators that act alike, whose shares of their effort are
judged (`models.effort`)."""

from dataclasses import replace

import numpy as np

from auvdiag_cli.vehicle.actuators import ROTOR, SET_POINT
from auvdiag_cli.vehicle.controller import ControllerSpec
from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError
from models.effort import EffortGroup
from models.effort_reach import as_table, balance, reach


def parse_effort_group(reader: TableReader, names: list[str]) -> EffortGroup:
    """``[[effort]]``: ``name``, ``actuators`` (two or more commands or outputs), optional
    ``factors`` (the frame's mixing factor of each, by magnitude), ``min_level`` (steady from
    this command level up) and ``window_s``."""
    members = reader.get("actuators", list)
    unknown = [m for m in members if m not in names]
    if unknown or len(members) < 2 or len(set(members)) != len(members):
        raise ProfileError(f"key '{reader.key('actuators')}' must name two or more distinct "
                           f"commands or outputs (the profile's: {', '.join(names)})")
    factors = reader.get("factors", list, [1.0] * len(members))
    if len(factors) != len(members) or not all(
            isinstance(f, int | float) and not isinstance(f, bool) and f != 0 for f in factors):
        raise ProfileError(f"key '{reader.key('factors')}' must hold one non-zero number per "
                           "actuator")
    min_level = reader.get("min_level", float, None)
    window = reader.get("window_s", float, None)
    for key, value in (("min_level", min_level), ("window_s", window)):
        if value is not None and value <= 0:
            raise ProfileError(f"key '{reader.key(key)}' must be positive, got {value}")
    return EffortGroup(reader.get("name", str), tuple(str(m) for m in members),
                       tuple(abs(float(f)) for f in factors), min_level, window)


def parse_effort_groups(rows: list[TableReader], kinds: dict[str, str]
                        ) -> tuple[EffortGroup, ...]:
    """The [[effort]] groups (``kinds``: each command's and output's kind), each of actuators
    of one kind: their shares compare like with like, and a departure is worded for that
    kind."""
    groups = []
    for reader in rows:
        group = parse_effort_group(reader, list(kinds))
        found = sorted({kinds[m] for m in group.members})
        if len(found) > 1 or SET_POINT in found:
            raise ProfileError(f"key '{reader.key('actuators')}' mixes kinds {', '.join(found)}:"
                               " an effort group holds actuators of one kind, never set points")
        # A multirotor's controller holds thrust, roll, pitch and yaw: four efforts, which
        # reach every direction of four rotors and no more.
        groups.append(replace(group, driven_alone=found == [ROTOR] and len(group.members) == 4))
    return tuple(groups)


TILTS = ("roll", "pitch")     # the moments a group's members balance by where they sit


def with_reach(groups: tuple[EffortGroup, ...], controller: ControllerSpec | None
               ) -> tuple[EffortGroup, ...]:
    """The groups, each with the reach of the controller's mix over its members where that
    misses directions of the group (`models.effort_reach`): the efforts the controller's
    loops drive, each member's factor on them; where it reaches every direction, the balance
    of the tilting moments (`models.effort_reach.balance`), and each member driven alone
    (`EffortGroup.driven_alone`: without a mix, a quadrotor's four rotors are)."""
    if controller is None:
        return groups
    held = controller.held_efforts
    placed = []
    for group in groups:
        if not all(m in controller.mix for m in group.members):
            placed.append(group)
            continue
        rows = np.array([[controller.mix[m].get(e, 0.0) for e in held] for m in group.members])
        projection = reach(rows)
        if projection is not None:
            placed.append(replace(group, reach=as_table(projection), driven_alone=False))
            continue
        group = replace(group, driven_alone=True)
        tilts = balance(np.array([[controller.mix[m].get(e, 0.0) for e in TILTS]
                                  for m in group.members]))
        placed.append(group if tilts is None else replace(group, balance=as_table(tilts)))
    return tuple(placed)

