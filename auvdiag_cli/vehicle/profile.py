"""Vehicle profiles: TOML files validated once into a typed `Profile`."""

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from adapters.signals import OPERATING, LogSources
from auvdiag_cli.vehicle.actuators import (
    ACTUATOR_KINDS,
    SET_POINT,
    Actuator,
    check_weakened,
    parse_actuators,
    parse_kind,
    parse_moved_by,
)
from auvdiag_cli.vehicle.controller import ControllerSpec
from auvdiag_cli.vehicle.controller_table import parse_controller
from auvdiag_cli.vehicle.effort_groups import parse_effort_groups, with_reach
from auvdiag_cli.vehicle.simulation_spec import SimulationSpec, parse_simulation
from auvdiag_cli.vehicle.sources import log_sources
from auvdiag_cli.vehicle.toml_reader import TableReader, positive
from auvdiag_cli.vehicle.tracking_table import parse_tracking
from auvdiag_errors import ProfileError
from models.effort import EffortGroup
from models.tracking import TrackingSpec

MISSION_MODE = "mission"
ROUTINE_THRESHOLDS = "routine"     # thresholds shared by every DMS without its own table


@dataclass(frozen=True)
class Command:
    """A command that drives the model, or (``[[outputs]]``) one only the effort check reads."""

    name: str
    component: str
    description: str
    kind: str = "thruster"       # an actuator kind (ACTUATOR_KINDS) or a set point
    unit: str = ""               # "": normalised (an actuator's full scale is 1)

    @property
    def failure(self) -> str:
        """How a failure of what it commands is said."""
        return ACTUATOR_KINDS.get(self.kind, "")


@dataclass(frozen=True)
class Input:
    """A measured quantity that drives the model beside the commands (a battery voltage, the
    attitude): replayed as logged, like them; never predicted, never judged, no actuator."""

    name: str
    unit: str
    description: str


@dataclass(frozen=True)
class Sensor:
    name: str
    component: str
    unit: str
    full_scale: float
    description: str
    truth_column: str | None = None     # its true value in a NAME.truth.csv, when one exists
    moved_by: tuple[str, ...] = ()     # the actuators (or command components) that move it
    # Judged only against the log's own beginning (a ground speed, with the day's wind): why.
    own_log_only: str | None = None
    # Judged only within a part's signature (`weakened`), never alone: why (None: alone too).
    signature_only: str | None = None
    # Judged by the change test only below the prediction, the way its parts fail: why.
    below_only: str | None = None


@dataclass(frozen=True)
class Navigation:
    """Which signals dead-reckon the track: a forward speed and a yaw rate."""

    speed: str
    yaw_rate: str


@dataclass(frozen=True)
class PatternRow:
    case: int
    b: dict[str, int]
    components: tuple[str, ...]


@dataclass(frozen=True)
class DiagnosisSequence:
    """A DMS: a fixed command history as steps of (duration_s, one command per actuator)."""

    name: str
    description: str
    steps: tuple[tuple[float, tuple[float, ...]], ...]

    @property
    def duration_s(self) -> float:
        return sum(duration for duration, _ in self.steps)


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    dt_s: float
    commands: tuple[Command, ...]
    sensors: tuple[Sensor, ...]
    window_samples: int
    decision_window_s: float
    thresholds: dict[str, dict[str, float]]
    pattern: tuple[PatternRow, ...]
    dms: dict[str, DiagnosisSequence]
    sources: dict[str, LogSources]   # per log family: ros, mavlink, dataflash
    source_path: str
    navigation: Navigation | None = None
    controller: ControllerSpec | None = None
    simulation: SimulationSpec | None = None
    # Not operating once every command has been neutral this long (None: no such rule).
    idle_after_s: float | None = None
    # The replay's prediction horizon: None chosen by `train`, inf the paper's free run.
    horizon_s: float | None = None
    # Actuators that act alike: each one's steady share of their effort is judged.
    effort_groups: tuple[EffortGroup, ...] = ()
    inputs: tuple[Input, ...] = ()        # measured inputs beside the commands ([[inputs]])
    # The parts that move the vehicle where they are not its commands ([[actuators]]).
    actuators: tuple[Actuator, ...] = ()
    # Actuator outputs read for the effort check only: a model driven by the controller's set
    # points does not read them, yet what each actuator carries is judged ([[outputs]]).
    outputs: tuple[Command, ...] = ()
    tracking: tuple[TrackingSpec, ...] = ()   # loops whose gain the change test judges

    @property
    def command_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.commands)

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(i.name for i in self.inputs)

    @property
    def output_names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.outputs)

    @property
    def effort_actuators(self) -> tuple[Command, ...]:
        """What an effort group may name: the commands, then the actuator outputs."""
        return self.commands + self.outputs

    @property
    def effort_names(self) -> tuple[str, ...]:
        return self.command_names + self.output_names

    @property
    def drive_names(self) -> tuple[str, ...]:
        """What the model is driven by: the commands, then the measured inputs."""
        return self.command_names + self.input_names

    @property
    def sensor_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.sensors)

    @property
    def full_scales(self) -> dict[str, float]:
        return {s.name: s.full_scale for s in self.sensors}

    def sensor(self, name: str) -> Sensor:
        return next(s for s in self.sensors if s.name == name)

    def thresholds_for(self, mode: str) -> dict[str, float]:
        """Thresholds of a DMS name or of the mission mode. A DMS without its own table uses
        the ``routine`` table when there is one; anything else the mission's."""
        if mode in self.thresholds:
            return self.thresholds[mode]
        if mode in self.dms and ROUTINE_THRESHOLDS in self.thresholds:
            return self.thresholds[ROUTINE_THRESHOLDS]
        return self.thresholds[MISSION_MODE]


def _horizon(matching: TableReader) -> float | None:
    """``[matching] horizon_s``: "auto" (the default), "free" or inf, or seconds."""
    value = matching.get("horizon_s", (str, float, int), "auto")
    if value == "auto":
        return None
    if value == "free":
        return math.inf
    if isinstance(value, str) or value <= 0:
        raise ProfileError("key 'matching.horizon_s' must be \"auto\", \"free\" or a positive "
                           f"number of seconds, got {value!r}")
    return float(value)


def _command(reader: TableReader, kinds: tuple[str, ...]) -> Command:
    return Command(reader.get("name", str), reader.get("component", str),
                   reader.get("description", str, ""), parse_kind(reader, "thruster", kinds),
                   reader.get("unit", str, ""))


def _rows(top: TableReader, key: str) -> list[TableReader]:
    """The rows of an optional array of tables."""
    return top.items(key) if key in top.table else []


def _signals(top: TableReader, actuators: tuple[Actuator, ...]
             ) -> tuple[tuple[Command, ...], tuple[Sensor, ...], tuple[Input, ...],
                        tuple[Command, ...], set[str]]:
    """The commands, sensors, inputs and outputs, and what may move a signal (`moved_by`)."""
    commands = tuple(_command(r, (*ACTUATOR_KINDS, SET_POINT)) for r in top.items("commands"))
    outputs = tuple(_command(r, tuple(ACTUATOR_KINDS)) for r in _rows(top, "outputs"))
    movers = {a.name for a in actuators} | {c.component for c in commands + outputs}
    sensors = tuple(
        Sensor(r.get("name", str), r.get("component", str), r.get("unit", str),
               positive(r, "full_scale"), r.get("description", str, ""),
               r.get("truth_column", str, None), parse_moved_by(r, movers),
               r.get("own_log_only", str, None), r.get("signature_only", str, None),
               r.get("below_only", str, None))
        for r in top.items("sensors"))
    check_weakened(actuators, sensors)
    inputs = tuple(Input(r.get("name", str), r.get("unit", str, ""), r.get("description", str, ""))
                   for r in _rows(top, "inputs"))
    if not commands or not sensors:
        raise ProfileError("key 'commands' and key 'sensors' need at least one entry each")
    signal_names = [c.name for c in commands + outputs] + [s.name for s in sensors] + [
        i.name for i in inputs]
    if len(set(signal_names)) != len(signal_names):
        raise ProfileError("signal names in 'commands', 'sensors', 'inputs' and 'outputs' must "
                           "be unique")
    if OPERATING in signal_names:
        raise ProfileError(f"signal name {OPERATING!r} is reserved for the operating flag "
                           "([sources.FAMILY] operating = {...})")
    return commands, sensors, inputs, outputs, movers


def _thresholds(table: TableReader, sensor_names: list[str]) -> dict[str, dict[str, float]]:
    thresholds = {mode: {name: positive(table.sub(mode), name) for name in sensor_names}
                  for mode in table.names()}
    if MISSION_MODE not in thresholds:
        raise ProfileError(f"missing key 'thresholds.{MISSION_MODE}'")
    return thresholds


def _navigation(nav: TableReader, sensor_names: list[str]) -> Navigation:
    navigation = Navigation(nav.get("speed", str), nav.get("yaw_rate", str))
    for key, name in (("speed", navigation.speed), ("yaw_rate", navigation.yaw_rate)):
        if name not in sensor_names:
            raise ProfileError(f"key 'navigation.{key}' names no sensor: {name!r}")
    return navigation


def parse_profile(data: dict[str, Any], source_path: str) -> Profile:
    """Validate a parsed TOML document into a `Profile`."""
    top = TableReader(data, "")
    vehicle = top.sub("vehicle")
    actuators = parse_actuators(top.items("actuators")) if "actuators" in data else ()
    commands, sensors, inputs, outputs, movers = _signals(top, actuators)
    sensor_names = [s.name for s in sensors]
    # A log may lack a measured input or an actuator output: the model then holds the input
    # at its typical value, and the effort check says it cannot judge.
    optional = [i.name for i in inputs] + [o.name for o in outputs]
    signal_names = [c.name for c in commands] + sensor_names + optional
    matching = top.sub("matching")
    window = matching.get("window_samples", int)
    if window < 1:
        raise ProfileError("key 'matching.window_samples' must be at least 1")
    thresholds = _thresholds(top.sub("thresholds"), sensor_names)
    components = ({c.component for c in commands + outputs} | {s.component for s in sensors}
                  | {a.name for a in actuators})
    pattern = _pattern(top.items("pattern") if "pattern" in data else [], sensor_names,
                       components)
    dms_table = top.sub("dms") if "dms" in data else TableReader({}, "dms")
    dms = {name: _dms(dms_table.sub(name), name, len(commands)) for name in dms_table.names()}
    sources_table = top.sub("sources")
    sources = {family: log_sources(sources_table.sub(family), signal_names, optional, family)
               for family in sources_table.names()}
    navigation = _navigation(top.sub("navigation"), sensor_names) if "navigation" in data \
        else None
    controller = parse_controller(top.sub("controller"), sensor_names,
                             [c.name for c in commands]) if "controller" in data else None
    profile = Profile(
        name=vehicle.get("name", str),
        description=vehicle.get("description", str, ""),
        dt_s=positive(vehicle, "dt_s"),
        commands=commands,
        sensors=sensors,
        window_samples=window,
        decision_window_s=matching.get("decision_window_s", float, 0.0),
        horizon_s=_horizon(matching),
        thresholds=thresholds,
        pattern=pattern,
        dms=dms,
        sources=sources,
        navigation=navigation,
        controller=controller,
        simulation=parse_simulation(top.sub("simulation"), [c.name for c in commands],
                                    sensor_names) if "simulation" in data else None,
        source_path=source_path,
        idle_after_s=positive(top.sub("operating"), "idle_after_s")
        if "operating" in data else None,
        effort_groups=with_reach(parse_effort_groups(
            _rows(top, "effort"), {c.name: c.kind for c in commands + outputs}), controller),
        inputs=inputs,
        outputs=outputs,
        actuators=actuators,
        tracking=parse_tracking(_rows(top, "tracking"), [c.name for c in commands], sensor_names,
                                movers, [o.name for o in outputs]),
    )
    top.check_all_read()
    return profile


def _pattern(rows: list[TableReader], sensor_names: list[str], components: set[str]
             ) -> tuple[PatternRow, ...]:
    """The optional pattern table; a row that repeats another's case or b vector is an
    error naming both rows."""
    pattern: list[PatternRow] = []
    for reader in rows:
        row = _pattern_row(reader, sensor_names, components)
        for earlier, other in zip(rows, pattern, strict=False):
            if other.case == row.case:
                raise ProfileError(f"key '{reader.key('case')}' repeats case {row.case} of "
                                   f"{earlier.where}")
            if other.b == row.b:
                raise ProfileError(f"key '{reader.key('b')}' repeats the b vector of "
                                   f"{earlier.where} (case {other.case})")
        pattern.append(row)
    return tuple(pattern)


def _pattern_row(reader: TableReader, sensor_names: list[str], components: set[str]
                 ) -> PatternRow:
    b_reader = reader.sub("b")
    unknown = [name for name in b_reader.names() if name not in sensor_names]
    if unknown:
        raise ProfileError(f"key '{b_reader.key(unknown[0])}' names no sensor (b has one bit "
                           f"per sensor: {', '.join(sensor_names)})")
    b = {}
    for name in sensor_names:
        bit = b_reader.get(name, int)
        if bit not in (0, 1):
            raise ProfileError(f"key '{b_reader.key(name)}' must be 0 or 1")
        b[name] = bit
    named = [str(c) for c in reader.get("components", list)]
    strangers = [c for c in named if c not in components]
    if strangers:
        raise ProfileError(f"key '{reader.key('components')}' names unknown component "
                           f"{strangers[0]!r} (the profile's: {', '.join(sorted(components))})")
    return PatternRow(reader.get("case", int), b, tuple(named))


def _dms(reader: TableReader, name: str, n_commands: int) -> DiagnosisSequence:
    steps = []
    for i, step in enumerate(reader.get("steps", list)):
        if not isinstance(step, list) or len(step) != n_commands + 1:
            raise ProfileError(
                f"key '{reader.key('steps')}[{i}]' must be [duration_s, {n_commands} commands]")
        duration, *levels = (float(v) for v in step)
        steps.append((duration, tuple(levels)))
    return DiagnosisSequence(name, reader.get("description", str, ""), tuple(steps))


# The package is installed as files: its folder is found without importlib.resources,
# whose import (tempfile, zipfile, ...) cost about 7 ms of every diagnosis.
BUILTIN_FOLDER = Path(__file__).parent / "profiles"


def builtin_profiles() -> tuple[str, ...]:
    """The names of the profiles shipped with auvdiag (auvdiag_cli/vehicle/profiles)."""
    return tuple(sorted(entry.name.removesuffix(".toml") for entry in BUILTIN_FOLDER.iterdir()
                        if entry.name.endswith(".toml")))


def profile_text(path: Path | None = None) -> tuple[str, str]:
    """A profile's TOML text and where it came from: a file, or a built-in profile by name
    (see `builtin_profiles`); None is the Twin-Burger of the paper."""
    name = "twin_burger" if path is None else str(path)
    if path is None or (name in builtin_profiles() and not path.exists()):
        resource = BUILTIN_FOLDER / f"{name}.toml"
        return resource.read_text(encoding="utf-8"), f"builtin:{name}"
    try:
        return path.read_text(encoding="utf-8"), str(path)
    except OSError as error:
        raise ProfileError(f"{path}: cannot read profile: {error.strerror} (built-in "
                           f"profiles: {', '.join(builtin_profiles())})") from None


def load_profile(path: Path | None = None) -> Profile:
    """Load a profile file, or a built-in profile by name (see `builtin_profiles`); None is
    the Twin-Burger of the paper."""
    text, where = profile_text(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ProfileError(f"{where}: not valid TOML: {error}") from None
    try:
        return parse_profile(data, where)
    except ProfileError as error:
        raise ProfileError(f"{where}: {error}") from None
