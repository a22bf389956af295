"""The parts that move a vehicle, beside the signals that drive its model: on a vehicle
whose model is driven by its controller's set points, the thrusters, rotors, control
surfaces and engines are not commands, yet they are what fails. A profile lists them in
`[[actuators]]` (name, kind, description) and says, per sensor, which of them move the
quantity it measures (`moved_by`): a relation that changes then names its part."""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol

from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError


class _Sensor(Protocol):
    """What the checks here read of a profile's sensor."""

    @property
    def name(self) -> str: ...
    @property
    def signature_only(self) -> str | None: ...
    @property
    def below_only(self) -> str | None: ...

# Each kind, and how its failure is said. A command may also be a controller's set point
# (SET_POINT): it drives the model, but nothing fails in it.
SET_POINT = "set_point"
CONTROL_SURFACE = "control_surface"
ROTOR = "rotor"
ACTUATOR_KINDS = {
    "thruster": "a damaged or fouled propeller, a weak motor, or a load near it",
    ROTOR: "a damaged propeller or a weak motor",
    CONTROL_SURFACE: "a surface stuck, loose or damaged, or its servo failing",
    "engine": "lost or reduced thrust",
}


# What one log of the vehicle is called in messages: a vehicle moved by rotors, surfaces or
# an engine flies; one moved by thrusters (or whose parts the profile does not say) dives.
FLYING_KINDS = (ROTOR, CONTROL_SURFACE, "engine")


def outing(kinds: Iterable[str]) -> str:
    """"flight" or "dive", from the kinds of the vehicle's commands and actuators."""
    parts = {k for k in kinds if k != SET_POINT}
    return "flight" if parts and parts <= set(FLYING_KINDS) else "dive"


@dataclass(frozen=True)
class Actuator:
    name: str
    kind: str
    description: str = ""
    # Its signature in the change test (`engine.change_signatures`): signal -> +1 or -1,
    # where its weakening leaves that signal above or below the prediction.
    weakened: tuple[tuple[str, float], ...] = ()

    @property
    def failure(self) -> str:
        return ACTUATOR_KINDS[self.kind]


def parse_kind(reader: TableReader, default: str, allowed: tuple[str, ...]) -> str:
    kind = reader.get("kind", str, default)
    if kind not in allowed:
        raise ProfileError(f"key '{reader.key('kind')}' must be one of {', '.join(allowed)}, "
                           f"got {kind!r}")
    return str(kind)


def parse_actuators(rows: list[TableReader]) -> tuple[Actuator, ...]:
    actuators = []
    for reader in rows:
        kind = parse_kind(reader, "", tuple(ACTUATOR_KINDS))
        actuators.append(Actuator(reader.get("name", str), kind,
                                  reader.get("description", str, ""), _weakened(reader)))
    names = [a.name for a in actuators]
    if len(set(names)) != len(names):
        raise ProfileError("actuator names in 'actuators' must be unique")
    return tuple(actuators)


def _weakened(reader: TableReader) -> tuple[tuple[str, float], ...]:
    entry = reader.get("weakened", dict, {})
    signs = []
    for name, value in entry.items():
        if isinstance(value, bool) or value not in (1, -1):
            raise ProfileError(f"key '{reader.key('weakened')}.{name}' must be 1 or -1 (the "
                               f"signal reads above or below the prediction), got {value!r}")
        signs.append((str(name), float(value)))
    return tuple(signs)


def check_weakened(actuators: Sequence[Actuator], sensors: Sequence[_Sensor]) -> None:
    """Every signal an actuator's `weakened` names is a sensor, and every sensor judged only
    within a signature is in one (else nothing would judge it) and not below only as well
    (it has no way of its own there)."""
    known = {s.name for s in sensors}
    for actuator in actuators:
        strangers = [name for name, _ in actuator.weakened if name not in known]
        if strangers:
            raise ProfileError(f"actuator {actuator.name!r}: 'weakened' names {strangers[0]!r}, "
                               f"which is no sensor (known: {', '.join(sorted(known))})")
    in_signatures = {name for actuator in actuators for name, _ in actuator.weakened}
    for index, sensor in enumerate(sensors):
        if sensor.signature_only and sensor.name not in in_signatures:
            raise ProfileError(f"key 'sensors[{index}].signature_only': {sensor.name!r} is in "
                               "no actuator's 'weakened', so nothing would judge it")
        if sensor.signature_only and sensor.below_only:
            raise ProfileError(f"key 'sensors[{index}].below_only': {sensor.name!r} is judged "
                               "only within a part's signature (signature_only), which is "
                               "judged one way already")


def parse_moved_by(reader: TableReader, known: set[str]) -> tuple[str, ...]:
    """A sensor's `moved_by`: actuators or command components, each known."""
    names = tuple(str(n) for n in reader.get("moved_by", list, []))
    strangers = [n for n in names if n not in known]
    if strangers:
        raise ProfileError(f"key '{reader.key('moved_by')}' names {strangers[0]!r}, which is "
                           f"no actuator or command component (known: "
                           f"{', '.join(sorted(known))})")
    return names
