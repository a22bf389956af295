"""`auvdiag init-profile`: a starting profile written from what a log holds.

The log's message types, fields and values are matched against what vehicles commonly log
(motor outputs, gyro rates, climb or depth rates, an armed flag); a field is proposed only
where it is in the log and, for commands and sensors, actually varies. Everything the log
cannot tell (units, full scales, which component fails how, thresholds) is written with a
``CHECK`` comment. The draft loads, and every signal in it resolves on the log it came from."""

import re
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from adapters import LogInventory, inventory, read_log
from adapters.autopilot_setup import AutopilotSetup, autopilot_setup
from adapters.csv_log import csv_rows
from adapters.fieldpath import is_field_path
from adapters.recognise import is_number
from adapters.signals import MOOS_SOURCE, MOOS_SOURCE_AUX, FieldSource, LogSources, TimeColumn
from auvdiag_cli.jobs.attitude_draft import angle_loops, angle_proposal, attitude_candidates
from auvdiag_cli.jobs.autopilot_outputs import (
    climb_source,
    output_channel,
    output_roles,
    role_groups,
    role_proposal,
)
from auvdiag_cli.jobs.autopilot_set_points import (
    attitude_loops,
    first_instance,
    pairing,
    set_point_pairs,
    set_point_proposal,
)
from auvdiag_cli.jobs.draft_groups import effort_groups, repeated
from auvdiag_cli.jobs.draft_names import described, draft_name
from auvdiag_cli.jobs.draft_text import (
    NEUTRAL,
    DraftGroup,
    Proposal,
    is_set_point,
    render_draft,
    signal_name,
    typical_level,
)
from auvdiag_cli.jobs.moos_draft import PID_OUTPUT, label, pid_output
from auvdiag_cli.jobs.operating_draft import draft_operating
from auvdiag_errors import LogError, UsageError

PWM_SCALE, PWM_CENTRE_US = 0.0025, 1500.0       # ArduPilot: 1500 µs neutral, ±400 µs full
COMMAND_NAME = re.compile(r"(servo\d+_raw|^C\d+$|pwm|thrust|motor|throttle|cmd|command)",
                          re.IGNORECASE)
COMMAND_TOPIC = re.compile(r"(cmd|command|thrust|motor|actuator|servo|pwm|RCOU|rc/out$)",
                           re.IGNORECASE)
SENSOR_NAME = re.compile(r"(rollspeed|pitchspeed|yawspeed|^Gyr[XYZ]$|angular_velocity\.[xyz]|"
                         r"^w_|gyro|climb|^CRt$|depth|heave|twist\.linear\.[xyz]|velocity|speed|"
                         r"flow|_rate|rate_)",
                         re.IGNORECASE)
# Estimator and bookkeeping fields whose names look like sensors but are not measurements.
NOT_A_SENSOR = re.compile(r"(variance|covariance|^req_|_count$|status|error|^RAW_|^SCALED_IMU|"
                          r"^EKF_|^REQUEST_|^PARAM|^DESIRED_)", re.IGNORECASE)
# A ROS message's header (its sequence number and stamp) says when, never what.
HEADER_FIELD = re.compile(r"header\.")
# A set point left unset (NaN: PX4 holding a position sets no velocity) more often than
# this drives no model.
MOSTLY_UNSET = 0.1
# A topic of a controller's set points (PX4's vehicle_rates_setpoint, mavros's setpoint_raw):
# its fields are what was asked, never what was measured nor what an actuator was told
# (its thrust).
SET_POINT_TOPIC = re.compile(r"setpoint|set_point", re.IGNORECASE)
# A clock's column, its unit perhaps beside it as CSV exports write it ("time (s)", "t [ms]").
TIME_NAME = re.compile(r"^(t|time|timestamp|stamp|time_\w+|\w+_time)"
                       r"(\s*[(\[]\s*(s|ms|us|ns)\s*[)\]])?$", re.IGNORECASE)
MAX_ARRAY_COMMANDS = 8          # thrusters looked for in one command array
HELD_SHARE = 0.5                # of consecutive samples equal: a field that holds its value


def _candidates(contents: LogInventory, family: str, every_field: bool = False,
                closed_loop: bool = False, pairs: Sequence[tuple[str, FieldSource]] = ()
                ) -> list[tuple[str, FieldSource]]:
    """(kind, source) for every field whose name or topic looks like a command or a sensor;
    ``every_field``: any other field is a sensor too (names this does not recognise);
    ``closed_loop``: an autopilot's set points (``pairs``, `set_point_pairs`) and what was
    measured beside them too."""
    found = [*pairs, *attitude_candidates(contents, family, closed_loop)]
    for topic in contents.topics:
        if topic.count < 2 or (family != "csv" and SET_POINT_TOPIC.search(topic.name)):
            continue                     # a set point is drafted only beside its measurement
        where = first_instance(topic)
        # A CSV column is a name, whatever it holds; other fields are paths into a message
        # (a damaged log's field names may not be).
        fields = (topic.fields or (topic.name,)) if family == "csv" else [
            field for field in topic.fields if is_field_path(field)
            and not HEADER_FIELD.match(field)
            and (family != "moos" or field not in (MOOS_SOURCE, MOOS_SOURCE_AUX))]
        for field in fields:
            named = label(topic.name, field, family)
            command = COMMAND_NAME.search(named) or (
                family in ("ros", "moos", "ulog") and COMMAND_TOPIC.search(topic.name)) or (
                family == "moos" and PID_OUTPUT.match(named))
            if command and (family != "mavlink" or topic.name == "SERVO_OUTPUT_RAW") and (
                    family != "dataflash" or topic.name == "RCOU"):
                # An array of commands is listed by its first element: try the next ones.
                elements = [field] if not field.endswith("[0]") else [
                    f"{field[:-3]}[{i}]" for i in range(MAX_ARRAY_COMMANDS)]
                found += [("command", FieldSource(topic.name, path, where=where))
                          for path in elements]
            elif not TIME_NAME.match(field) and (every_field or SENSOR_NAME.search(
                    described(topic.name, named, family))) and not (
                    NOT_A_SENSOR.search(named) or NOT_A_SENSOR.search(topic.name)):
                found.append(("sensor", FieldSource(topic.name, field, where=where)))
    return found


def guess_time_column(contents: LogInventory, path: Path) -> TimeColumn | None:
    """For a CSV log: the column named like a clock, its unit guessed from its values."""
    named = [t.name for t in contents.topics if TIME_NAME.match(t.name)]
    if not named:
        return None
    rows = csv_rows(path)
    header = [cell.strip() for cell in next(rows)]
    at = header.index(named[0])
    sample = [row[at] for _, row in zip(range(200), rows, strict=False) if len(row) > at]
    numbers = np.array([float(v) for v in sample if is_number(v)])
    if numbers.size == 0:
        return TimeColumn(named[0], "iso")
    whole = numbers == np.floor(numbers)
    if whole.all() and numbers.max() <= 235959 and np.unique(numbers).size < numbers.size / 2:
        return TimeColumn(named[0], "hhmmss")
    return TimeColumn(named[0], _clock_unit(named[0], numbers))


UNIT_SUFFIX = re.compile(r"(?:_|[(\[])\s*(s|ms|us|ns)\s*[)\]]?$", re.IGNORECASE)
SECONDS_PER = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}


def _sensor_unit(field: str) -> str:
    """The unit a motion field's name says: angular rates (ATTITUDE rollspeed, IMU GyrX,
    angular_velocity) in rad/s, speeds and velocities (VFR_HUD groundspeed, twist.linear)
    in m/s; "?" where the name says nothing."""
    if re.search(r"(roll|pitch|yaw)speed$|^Gyr|angular|gyro", field, re.IGNORECASE):
        return "rad/s"
    if re.search(r"speed$|velocity|linear\.|^v[xyz]$|^V[NED]$|heave$|height_rate$", field,
                 re.IGNORECASE):
        return "m/s"
    return "?"


def _clock_unit(name: str, numbers: np.ndarray) -> str:
    """The unit the column's name says (time_us); else an epoch's by its size; else the one
    that puts the median sample interval between 0.1 ms and 10 s (a clock since boot)."""
    suffix = UNIT_SUFFIX.search(name)
    if suffix:
        return suffix.group(1).lower()
    largest = float(np.abs(numbers).max())
    if largest > 1e11:
        return "ns" if largest > 1e17 else "us" if largest > 1e14 else "ms"
    steps = np.diff(numbers)
    step = float(np.median(steps[steps > 0])) if (steps > 0).any() else 0.0
    return next((unit for unit, seconds in SECONDS_PER.items()
                 if 1e-4 <= step * seconds <= 10.0), "s")


def _read_each(path: Path, family: str, sources: dict[str, FieldSource],
               time: TimeColumn | None) -> dict[str, np.ndarray]:
    """The values of every source that reads on this log, in one pass (a source the log
    does not fill reads nothing); one by one only where the log refuses them together."""
    def read(chosen: dict[str, FieldSource]) -> dict[str, np.ndarray]:
        signals = read_log(path, {family: LogSources(
            chosen, time=time, optional=frozenset(chosen), tentative=True)})
        return {name: series.values for name, series in signals.series.items()}

    try:
        return read(sources)
    except LogError:
        values: dict[str, np.ndarray] = {}
        for name, source in sources.items():
            try:
                values |= read({name: source})
            except LogError:
                continue
        return values


def _holds_its_value(series: np.ndarray) -> bool:
    """Most consecutive samples equal: a command held between changes (set points, stick
    positions, outputs logged faster than they change), rarely a measurement's noise."""
    finite = series[np.isfinite(series)]
    return finite.size > 2 and float(np.mean(np.diff(finite) == 0)) >= HELD_SHARE


def _moves(series: np.ndarray) -> bool:
    """Whether the field takes two values or more (its spread would overflow on a damaged
    log's huge ones)."""
    finite = series[np.isfinite(series)]
    return finite.size >= 2 and bool(finite.max() > finite.min())


def _proposals(path: Path, family: str, contents: LogInventory, time: TimeColumn | None,
               setup: AutopilotSetup | None, every_field: bool = False,
               guess_commands: bool = False, closed_loop: bool = False
               ) -> tuple[list[Proposal], list[Proposal], list[DraftGroup]]:
    """``every_field``: fields with unknown names are sensors; ``guess_commands``: those of
    them that hold their value between changes are commands (marked CHECK);
    ``closed_loop``: an autopilot's set points (`SET_POINT_PAIRS`) are commands;
    ``setup``: what an ArduPilot log says of its vehicle (a copter's motors by output)."""
    found = set_point_pairs(contents, family) if closed_loop else []
    raw = {f"{kind}:{source.topic}:{source.field}:{source.angle}": (kind, source)
           for kind, source in _candidates(contents, family, every_field, closed_loop, found)}
    values = _read_each(path, family, {key: src for key, (_, src) in raw.items()}, time)
    # Only where the set point and what was measured beside it are both in the log.
    pairs = {(s.topic, s.field) for _, s in found}
    roles = output_roles(setup, sorted({c for kind, source in raw.values()
                                        if kind == "command"
                                        and (c := output_channel(source)) is not None}))
    commands, sensors = [], []
    command_values: list[np.ndarray] = []
    for key, (kind, source) in raw.items():
        series = values.get(key)
        if series is None or not _moves(series) or (
                kind == "set_point" and np.isnan(series).mean() > MOSTLY_UNSET):
            continue                   # not in the log, never moves, or not set (PX4: NaN)
        called = label(source.topic, source.field, family)
        name = draft_name(source, called, family)
        channel = output_channel(source) if kind == "command" else None
        paired = pairing(source, family) if (source.topic, source.field) in pairs else None
        if paired is not None:
            name = paired[2]
        guessed = guess_commands and kind != "command" and _holds_its_value(series)
        proposal: Proposal | None
        if source.angle:                    # an attitude angle from a logged quaternion
            proposal = angle_proposal(source, series, family)
            if not proposal.set_point:
                sensors.append(proposal)
                continue
        elif roles and channel is not None:
            # A copter's or a plane's output: what its log says it drives, or nothing
            # the model needs (a camera mount, a light).
            proposal = None if channel not in roles else role_proposal(roles[channel],
                                                                       source, series)
        elif kind == "set_point" and paired is not None:
            proposal = set_point_proposal(name, source, *paired[:2])
        elif kind == "command" or guessed:
            proposal = (family == "moos" and pid_output(source, series)) or _command(
                name, source, series, guessed)
        else:
            sensors.append(_sensor(name, described(source.topic, called, family), source,
                                   series, paired, setup))
            continue
        if proposal is not None:
            commands.append(proposal)
            command_values.append(series * proposal.source.scale + proposal.source.offset)
    named = _unique(commands + sensors)
    commands, sensors = named[:len(commands)], named[len(commands):]
    if roles:
        return commands, sensors, role_groups(commands, roles)
    return commands, sensors, [DraftGroup(g) for g in effort_groups(
        commands, repeated(commands, command_values), command_values)]


def _command(name: str, source: FieldSource, series: np.ndarray, guessed: bool) -> Proposal:
    """A command of a vehicle the log says nothing of: PWM about 1500 µs as ArduPilot maps a
    thruster's, anything else as logged."""
    pwm = 800 <= float(np.nanmedian(series)) <= 2200
    converted = replace(source, scale=PWM_SCALE, offset=-PWM_CENTRE_US * PWM_SCALE) \
        if pwm else source
    check = ("PWM µs mapped as ArduPilot does, (pwm - 1500) / 400: check the neutral "
             "and the direction; remove outputs that are no thruster (lights, camera "
             "mount)" if pwm else "should run -1 … 1: set scale and offset")
    if guessed:
        check = ("not recognised by its name: proposed as a command because it holds "
                 "its value between changes, as commands do; " + check)
    value = series * converted.scale + converted.offset
    return Proposal(name, converted, "1", check, level=typical_level(value),
                    two_way=bool((value < -NEUTRAL).any()))


def _sensor(name: str, named: str, source: FieldSource, series: np.ndarray,
            paired: tuple[float, str, str | None] | None, setup: AutopilotSetup | None) -> Proposal:
    """``named``: what the field is called (`moos_draft.label`)."""
    unit = _sensor_unit(named) if paired is None else paired[1]
    check = "unit and sign" + ("" if unit != "?" else ": no unit is known for it")
    if paired is not None:
        source, check = replace(source, scale=paired[0]), "as its set point's"
    elif not SENSOR_NAME.search(named):
        check = ("not recognised by its name: keep it only if it measures the "
                 "vehicle's motion (remove battery, position fixes, bookkeeping); " + check)
    if source.field in ("climb", "CRt") and paired is None:
        # Measured beside its set point (DCRt), it keeps the set point's sign.
        source, unit, check = climb_source(source, setup)
    full_scale = float(np.nanpercentile(np.abs(series * source.scale), 99)) * 2
    return Proposal(name, source, unit, check, _nice(full_scale))


def _unique(proposals: list[Proposal]) -> list[Proposal]:
    """Names told apart: a field name that several topics share takes its topic's last part
    (nav_info/roll `commanded` -> roll_commanded); one still alike a count."""
    shared = {p.name for p in proposals if [q.name for q in proposals].count(p.name) > 1}
    proposals = [replace(p, name=signal_name("", f"{p.source.topic.rsplit('/', 1)[-1]}_"
                                                  f"{p.name}")) if p.name in shared else p
                 for p in proposals]
    seen: dict[str, int] = {}
    unique = []
    for proposal in proposals:
        count = seen.get(proposal.name, 0)
        seen[proposal.name] = count + 1
        unique.append(replace(proposal, name=f"{proposal.name}_{count}") if count else proposal)
    return unique


def _nice(value: float) -> float:
    if not np.isfinite(value) or value <= 0:
        return 1.0
    exponent = 10.0 ** np.floor(np.log10(value))
    return float(next(step * exponent for step in (1, 2, 5, 10) if step * exponent >= value))


def _clock_reference(family: str, contents: LogInventory) -> FieldSource | None:
    """A UTC time the log carries (a ROS TimeReference, as mavros publishes the autopilot's
    GPS time), where it has one: it dates a log whose own clock is off."""
    if family != "ros":
        return None
    topic = next((t.name for t in contents.topics
                  if {"time_ref.sec", "time_ref"} & set(t.fields)), None)
    return None if topic is None else FieldSource(topic, "time_ref.sec")


def draft_profile(path: Path, name: str, closed_loop: bool = False) -> str:
    """The text of a starting profile for the vehicle that wrote the log at ``path``;
    ``closed_loop``: a model driven by the autopilot's set points, the motor outputs read for
    the effort check only (a log whose set points are named as such is drafted so
    anyway)."""
    contents, family = inventory(path)
    time = guess_time_column(contents, path) if family == "csv" else None
    if family == "csv" and time is None:
        raise UsageError(f"{path}: no column is named like a clock (time, timestamp, …): "
                         "write [sources.csv] time = { column, unit } by hand")
    setup = autopilot_setup(path, family)
    commands, sensors, groups = _proposals(path, family, contents, time, setup,
                                           closed_loop=closed_loop)
    if closed_loop and not any(is_set_point(c) for c in commands):
        raise UsageError(f"{path}: --closed-loop found no controller set point that varies "
                         "in this log (ArduPilot DataFlash ATT DesRoll, RATE RDes, CTUN DCRt …; "
                         "ArduPilot telemetry NAV_CONTROLLER_OUTPUT nav_roll, nav_pitch; "
                         "PX4 ULog vehicle_rates_setpoint, vehicle_local_position_setpoint, "
                         "tecs_status …; or fields named commanded, desired, setpoint or "
                         "target)")
    if not commands or not sensors:   # names it does not know: every field that varies
        commands, sensors, groups = _proposals(path, family, contents, time, setup,
                                               every_field=True,
                                               guess_commands=not commands)
    if not commands or not sensors:
        what = ("command (none is named like a motor output, thrust or PWM, and none holds "
                "its value between changes as commands do)" if not commands else "sensor")
        raise UsageError(f"{path}: found no {what} field that varies in this log; write its "
                         "[[commands]] and [[sensors]] and their [sources] entries by hand "
                         "(`auvdiag inspect LOG` lists the fields; docs/vehicles.md has a complete "
                         "minimal profile)")
    operating = draft_operating(family, contents,
                                lambda sources: _read_each(path, family, sources, None))
    return render_draft(path, name, family, commands, sensors, operating, time, groups,
                        attitude_loops(commands, sensors) + angle_loops(
                            {p.name for p in [*commands, *sensors]}, family),
                        _clock_reference(family, contents),
                        "" if setup is None else setup.evidence)

