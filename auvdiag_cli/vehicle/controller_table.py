"""``[controller]`` in a profile: the controller `auvdiag simulate` flies the vehicle with
(its kind, the sensors its loops close on, the mix of its efforts into commands, gains)."""

from dataclasses import fields

from auvdiag_cli.vehicle.controller import (
    CONTROLLER_KINDS,
    EFFORTS,
    ControllerGains,
    ControllerSpec,
)
from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError


def parse_controller(reader: TableReader, sensor_names: list[str], command_names: list[str]
                ) -> ControllerSpec:
    kind = reader.get("kind", str)
    if kind not in CONTROLLER_KINDS:
        raise ProfileError(f"key '{reader.key('kind')}' must be one of {CONTROLLER_KINDS}")
    for key in ("speed", "yaw_rate", "heave", "roll_rate", "pitch_rate", "sway"):
        if key in reader.table and reader.get(key, str) not in sensor_names:
            raise ProfileError(f"key '{reader.key(key)}' names no sensor")
    if kind == "turn-then-go" and "speed" not in reader.table:
        raise ProfileError(f"key '{reader.key('speed')}' is missing: a turn-then-go "
                           "controller needs a speed sensor")
    mix_table = reader.sub("mix")
    mix = {}
    for command in mix_table.names():
        if command not in command_names:
            raise ProfileError(f"key '{mix_table.key(command)}' names no command")
        row = mix_table.sub(command)
        for effort in row.names():
            if effort not in EFFORTS:
                raise ProfileError(f"key '{row.key(effort)}' must be one of {EFFORTS}")
        mix[command] = {effort: row.get(effort, float) for effort in row.table}
    gains_reader = reader.sub("gains") if "gains" in reader.table else TableReader({}, "gains")
    known = {f.name for f in fields(ControllerGains)}
    gains = {}
    for name in gains_reader.names():
        if name not in known:
            raise ProfileError(f"key '{reader.key('gains')}.{name}' is not a gain of "
                               f"{kind} (known: {', '.join(sorted(known))})")
        gains[name] = gains_reader.get(name, float)
    return ControllerSpec(kind, reader.get("speed", str, None), reader.get("yaw_rate", str),
                          mix, ControllerGains(**gains), reader.get("heave", str, None),
                          -1.0 if reader.get("heave_up", bool, False) else 1.0,
                          reader.get("roll_rate", str, None), reader.get("pitch_rate", str, None),
                          reader.get("sway", str, None))
