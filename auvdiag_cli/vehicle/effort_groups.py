"""``[[effort]]`` in a profile: actuators that act alike, whose shares of their effort are
judged (`models.effort`)."""

from auvdiag_cli.vehicle.actuators import SET_POINT
from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError
from models.effort import EffortGroup


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
        groups.append(group)
    return tuple(groups)
