"""``[[tracking]]`` in a profile: a loop of the controller whose gain the change test judges
(`models.tracking`)."""

from collections.abc import Sequence

from auvdiag_cli.vehicle.actuators import parse_moved_by
from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError
from models.tracking import TrackingSpec


def parse_tracking(rows: Sequence[TableReader], commands: Sequence[str],
                   sensors: Sequence[str], movers: set[str]) -> tuple[TrackingSpec, ...]:
    """Each ``[[tracking]]``: ``name`` (a name no signal has), ``set_point`` (a command),
    ``measured`` and optional ``rate`` (sensors), ``moved_by`` (the parts that make the
    rate) and ``description``."""
    loops: list[TrackingSpec] = []
    for reader in rows:
        name = reader.get("name", str)
        if name in {*commands, *sensors, *(loop.name for loop in loops)}:
            raise ProfileError(f"key '{reader.key('name')}': {name!r} is already the name of "
                               "a signal or of another loop")
        spec = TrackingSpec(name, reader.get("set_point", str), reader.get("measured", str),
                            reader.get("rate", str, None), parse_moved_by(reader, movers),
                            reader.get("description", str, ""))
        if spec.set_point not in commands:
            raise ProfileError(f"key '{reader.key('set_point')}' names no command: "
                               f"{spec.set_point!r}")
        for key, signal in (("measured", spec.measured), ("rate", spec.rate)):
            if signal is not None and signal not in sensors:
                raise ProfileError(f"key '{reader.key(key)}' names no sensor: {signal!r}")
        loops.append(spec)
    return tuple(loops)
