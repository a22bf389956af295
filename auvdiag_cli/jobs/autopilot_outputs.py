"""What each servo output of an ArduPilot copter or plane drives, from what its log says
(`adapters.autopilot_setup`): the output's function (SERVOn_FUNCTION: motor 1-12, aileron,
elevator, rudder, throttle …), and how its PWM maps to a command (a motor's MOT_PWM_MIN …
MOT_PWM_MAX to 0 … 1; a surface's SERVOn_TRIM ± half its SERVOn_MIN … SERVOn_MAX to −1 …
1). Where the log holds no parameters, the firmware's defaults for its frame (ArduCopter:
motor N on output N; ArduPlane: aileron, elevator, throttle, rudder on outputs 1-4), said
as such. A sub, a rover or an unknown vehicle gets no roles: the draft's marine defaults
(thrusters, 1500 µs neutral) hold there."""

import re
from dataclasses import dataclass, replace

import numpy as np

from adapters.autopilot_setup import AutopilotSetup
from adapters.signals import FieldSource
from auvdiag_cli.jobs.draft_text import DraftGroup, Proposal, typical_level

CHANNEL = re.compile(r"^(?:C|servo)(\d+)(?:_raw)?$")
COPTER_PWM = (1000.0, 2000.0)              # MOT_PWM_MIN/MAX when unset
SERVO_RANGE = (1100.0, 1500.0, 1900.0)     # SERVOn_MIN, _TRIM, _MAX defaults
# SERVOn_FUNCTION of a plane's outputs -> (name, kind); 33-40, 82-85 are motors 1-12.
PLANE_FUNCTIONS = {4: ("aileron", "control_surface"), 19: ("elevator", "control_surface"),
                   21: ("rudder", "control_surface"), 24: ("flaperon_left", "control_surface"),
                   25: ("flaperon_right", "control_surface"),
                   77: ("elevon_left", "control_surface"),
                   78: ("elevon_right", "control_surface"),
                   79: ("vtail_left", "control_surface"), 80: ("vtail_right", "control_surface"),
                   70: ("throttle", "engine"), 73: ("throttle_left", "engine"),
                   74: ("throttle_right", "engine")}
PLANE_DEFAULTS = {1: 4, 2: 19, 3: 70, 4: 21}    # ArduPlane's outputs 1-4 out of the box
ONE_WAY_KINDS = ("rotor", "engine")
# Outputs of one function that act alike: their shares of the effort are judged.
GROUPED = {"aileron": "ailerons", "throttle": "engines"}
GROUP_SAID = {"rotors": "The frame's motors, as the log's setup says",
              "ailerons": "The outputs the log's setup gives the ailerons",
              "engines": "The outputs the log's setup gives the throttle"}


@dataclass(frozen=True)
class OutputRole:
    name: str              # "motor_1", "aileron_1", "throttle"
    kind: str              # a profile command kind: rotor, control_surface, engine
    scale: float           # PWM µs -> command
    offset: float
    group: str | None      # the [[effort]] group it belongs in
    says: str              # what the log said of it, for the draft's comment

    def source(self, logged: FieldSource) -> FieldSource:
        return replace(logged, scale=self.scale, offset=self.offset)


def output_channel(source: FieldSource) -> int | None:
    """The output number of an ArduPilot servo output field (RCOU C3, servo3_raw)."""
    if source.topic not in ("RCOU", "SERVO_OUTPUT_RAW"):
        return None
    found = CHANNEL.match(source.field)
    return int(found.group(1)) if found else None


def _function(setup: AutopilotSetup, channel: int) -> float | None:
    for name in (f"SERVO{channel}_FUNCTION", f"RC{channel}_FUNCTION"):
        value = setup.parameter(name)
        if value is not None:
            return value
    return None


def _motor(function: float) -> int | None:
    number = int(function)
    return number - 32 if 33 <= number <= 40 else number - 73 if 82 <= number <= 85 else None


def output_roles(setup: AutopilotSetup | None, channels: list[int]) -> dict[int, OutputRole]:
    """Each of ``channels`` that drives a copter's motor or a plane's surface or engine, with
    its role; empty where the log says the vehicle is neither (or nothing)."""
    if setup is None or setup.vehicle not in ("copter", "plane"):
        return {}
    functions = {c: _function(setup, c) for c in channels}
    known = any(f is not None for f in functions.values())
    return _copter(setup, functions, known) if setup.vehicle == "copter" \
        else _plane(setup, functions, known)


def _copter(setup: AutopilotSetup, functions: dict[int, float | None], known: bool
            ) -> dict[int, OutputRole]:
    low, high = _copter_pwm(setup)
    roles = {}
    for channel, function in functions.items():
        motor = _motor(function) if function is not None else \
            channel if not known and setup.motors and channel <= setup.motors else None
        if motor is None:
            continue
        said = (f"SERVO{channel}_FUNCTION {function:g}" if function is not None else
                f"output {channel}, the default of a {setup.frame or f'{setup.motors}-motor'}"
                " frame")
        roles[channel] = OutputRole(f"motor_{motor}", "rotor", 1 / (high - low),
                                    -low / (high - low), "rotors",
                                    f"motor {motor} ({said}); PWM {low:g} … {high:g} µs to "
                                    f"0 … 1{_pwm_said(setup)}")
    return roles


def _copter_pwm(setup: AutopilotSetup) -> tuple[float, float]:
    """MOT_PWM_MIN/MAX; where both are zero, ArduCopter takes the throttle input's range."""
    for low_name, high_name in (("MOT_PWM_MIN", "MOT_PWM_MAX"), ("RC3_MIN", "RC3_MAX")):
        low, high = setup.parameter(low_name), setup.parameter(high_name)
        if low and high and high > low:
            return low, high
    return COPTER_PWM


def _pwm_said(setup: AutopilotSetup) -> str:
    if setup.parameter("MOT_PWM_MIN") or setup.parameter("RC3_MIN"):
        return " (the log's parameters)"
    return " (MOT_PWM_MIN/MAX not in the log: ArduCopter's defaults, check yours)"


def _plane(setup: AutopilotSetup, functions: dict[int, float | None], known: bool
           ) -> dict[int, OutputRole]:
    chosen = {c: f if known else PLANE_DEFAULTS.get(c) for c, f in functions.items()}
    named = {c: PLANE_FUNCTIONS[int(f)] for c, f in chosen.items()
             if f is not None and int(f) in PLANE_FUNCTIONS}
    roles = {}
    for channel, (name, kind) in named.items():
        alike = [c for c, (other, _) in named.items() if other == name]
        label = name if len(alike) == 1 else f"{name}_{alike.index(channel) + 1}"
        low, trim, high = (setup.parameter(f"SERVO{channel}_{part}") or default
                           for part, default in zip(("MIN", "TRIM", "MAX"), SERVO_RANGE,
                                                    strict=True))
        one_way = kind in ONE_WAY_KINDS
        scale = 1 / (high - low) if one_way else 2 / (high - low)
        origin = low if one_way else trim
        said = (f"SERVO{channel}_FUNCTION {chosen[channel]:g}" if known
                else "ArduPlane's default output")
        roles[channel] = OutputRole(
            label, kind, scale, -origin * scale, GROUPED.get(name) if len(alike) > 1 else None,
            f"{name.replace('_', ' ')} ({said}); PWM "
            + (f"{low:g} … {high:g} µs to 0 … 1" if one_way
               else f"{trim:g} ± {(high - low) / 2:g} µs to -1 … 1 (check the direction)"))
    return roles


def role_proposal(role: OutputRole, source: FieldSource, series: np.ndarray) -> Proposal:
    return Proposal(role.name, role.source(source), "1", role.says,
                    level=typical_level(series * role.scale + role.offset),
                    two_way=role.kind not in ONE_WAY_KINDS, kind=role.kind)


def role_groups(commands: list[Proposal], roles: dict[int, OutputRole]) -> list[DraftGroup]:
    """The outputs the log says act alike (a copter's motors, a plane's two ailerons)."""
    drafted = {p.name for p in commands}
    groups: dict[str, list[str]] = {}
    for role in roles.values():
        if role.group is not None and role.name in drafted:
            groups.setdefault(role.group, []).append(role.name)
    return [DraftGroup(members, name, GROUP_SAID[name]) for name, members in groups.items()
            if len(members) > 1]


def climb_source(source: FieldSource, setup: AutopilotSetup | None) -> tuple[FieldSource, str, str]:
    """A climb rate (VFR_HUD climb, CTUN CRt in cm/s) as the vehicle's kind counts it: up
    positive for an aircraft, down positive (a depth rate) for a sub or an unknown vehicle."""
    centimetres = source.field == "CRt"
    if setup is not None and setup.vehicle in ("copter", "plane", "rover"):
        return (replace(source, scale=0.01 if centimetres else 1.0), "m/s",
                f"up positive (a {setup.vehicle}" + (", CTUN CRt in cm/s)" if centimetres
                                                     else ")"))
    return (replace(source, scale=-0.01 if centimetres else -1.0), "m/s",
            "down positive (the log's climb rate negated"
            + (", CTUN CRt in cm/s)" if centimetres else ")"))

