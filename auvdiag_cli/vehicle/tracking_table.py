"""``[[tracking]]`` in a profile: a loop of the controller whose gain the change test judges
(`models.tracking`)."""

from collections.abc import Sequence

from auvdiag_cli.vehicle.actuators import parse_moved_by
from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError
from models.tracking import TrackingSpec


def parse_tracking(rows: Sequence[TableReader], commands: Sequence[str],
                   sensors: Sequence[str], movers: set[str],
                   outputs: Sequence[str] = ()) -> tuple[TrackingSpec, ...]:
    """Each ``[[tracking]]``: ``name`` (a name no signal has); what the loop answers: either
    ``set_point`` (a command) less ``measured`` (a sensor), or ``drive`` (outputs or
    commands: the demand of one part); ``rate`` (a sensor; optional with ``measured``),
    ``moved_by`` (the parts that make the rate), optional ``window_s`` and
    ``description``."""
    loops: list[TrackingSpec] = []
    for reader in rows:
        name = reader.get("name", str)
        if name in {*commands, *sensors, *outputs, *(loop.name for loop in loops)}:
            raise ProfileError(f"key '{reader.key('name')}': {name!r} is already the name of "
                               "a signal or of another loop")
        drive = tuple(str(n) for n in reader.get("drive", list, []))
        set_point = reader.get("set_point", str, None if drive else ...)
        measured = reader.get("measured", str, None if drive else ...)
        spec = TrackingSpec(name, set_point, measured, reader.get("rate", str, None),
                            parse_moved_by(reader, movers), reader.get("description", str, ""),
                            drive, reader.get("window_s", float, 0.0))
        _check_names(reader, spec, commands, sensors, outputs)
        loops.append(spec)
    return tuple(loops)


def _check_names(reader: TableReader, spec: TrackingSpec, commands: Sequence[str],
                 sensors: Sequence[str], outputs: Sequence[str]) -> None:
    if spec.drive and (spec.set_point is not None or spec.measured is not None):
        raise ProfileError(f"key '{reader.key('drive')}': a loop answers a drive or a set "
                           "point less a measured value, not both")
    if spec.drive and spec.rate is None:
        raise ProfileError(f"key '{reader.key('drive')}': a loop on a drive needs its "
                           "'rate' (a sensor)")
    for driver in spec.drive:
        if driver not in {*commands, *outputs}:
            raise ProfileError(f"key '{reader.key('drive')}' names no output or command: "
                               f"{driver!r}")
    if spec.set_point is not None and spec.set_point not in commands:
        raise ProfileError(f"key '{reader.key('set_point')}' names no command: "
                           f"{spec.set_point!r}")
    named: dict[str, str | None] = {"measured": spec.measured, "rate": spec.rate}
    for key, signal in named.items():
        if signal is not None and signal not in sensors:
            raise ProfileError(f"key '{reader.key(key)}' names no sensor: {signal!r}")
    if spec.window_s < 0:
        raise ProfileError(f"key '{reader.key('window_s')}' must be positive")
