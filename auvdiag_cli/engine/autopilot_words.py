"""What the vehicle's own software said while it operated (`adapters.autopilot_messages`),
beside the diagnosis: an autopilot that wrote "Potential Thrust Loss (3)" or "Leak
Detected" has judged the log too, and a report that found nothing there must say so. The
words never change the verdict; they are lined up with it."""

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from adapters.signals import AutopilotMessage

WARNING_SEVERITY = 4          # MAV_SEVERITY_WARNING: this and the more severe are trouble
# The words of a disarm ("Crash: Disarming") come as the operating time ends.
AFTER_OPERATING_S = 2.0
# For texts kept without a severity (a DataFlash MSG record): words of ArduPilot's and PX4's
# warnings, and words of a warning that clears.
TROUBLE = re.compile(r"thrust loss|crash|leak|failsafe|fail|emergency|error|glitch|lost|"
                     r"unhealthy|vibration|battery|variance|critical|parachute|collision|"
                     r"fence breach", re.IGNORECASE)
CLEARED = re.compile(r"\b(cleared|resolved|restored|recovered)\b", re.IGNORECASE)
SHOWN = 3                     # alarms a sentence quotes; the report lists them all
SEVERITY_WORDS = {0: "emergency", 1: "alert", 2: "critical", 3: "error", 4: "warning"}
# ArduCopter's thrust-loss check names the motor it drives to full output to make up for a
# lost one, by its motor number: the actuator a profile names motor_N.
THRUST_LOSS = re.compile(r"thrust loss \((\d+)\)", re.IGNORECASE)


def is_alarm(message: AutopilotMessage) -> bool:
    if CLEARED.search(message.text):
        return False
    if message.severity is not None:
        return message.severity <= WARNING_SEVERITY
    return TROUBLE.search(message.text) is not None


@dataclass(frozen=True)
class SaidAlarm:
    """One text of trouble, as often as the autopilot repeated it."""

    text: str
    severity: int | None
    first_s: float               # seconds from the log's start
    last_s: float
    times: int


@dataclass(frozen=True)
class AutopilotSaid:
    alarms: tuple[SaidAlarm, ...]      # by first time
    other_messages: int                # what it said while operating that reports no trouble
    # Statuses already wrong at their first report (`AutopilotMessage.standing`): how the
    # log began, whether the vehicle operated then or not; never taken for news of it.
    standing: tuple[SaidAlarm, ...] = ()

    @property
    def motors_named(self) -> tuple[str, ...]:
        """The actuators the autopilot's own thrust-loss check named (motor_N)."""
        found = (THRUST_LOSS.search(a.text) for a in self.alarms)
        return tuple(dict.fromkeys(f"motor_{m.group(1)}" for m in found if m))

    def quoted(self, onset_s: float | None = None) -> str:
        """The first texts of trouble, each with its time (from the onset where given)."""
        return "; ".join(_quoted(a, onset_s) for a in self.alarms[:SHOWN]) + (
            f"; and {len(self.alarms) - SHOWN} more" if len(self.alarms) > SHOWN else "")

    def describe(self, fault: bool, onset_s: float | None, component: str | None = None
                 ) -> str:
        return self._news(fault, onset_s, component) + self.standing_text()

    def _news(self, fault: bool, onset_s: float | None, component: str | None) -> str:
        if not self.alarms:
            return "no warning or error while the vehicle operated" + (
                f" ({self.other_messages} other message(s))" if self.other_messages else "")
        quoted = self.quoted(onset_s if fault else None)
        more = " in the report" if len(self.alarms) > SHOWN else ""
        if fault:
            return quoted + more + _agreement(self.motors_named, component)
        return (f"reported trouble this diagnosis did not find: {quoted}{more}: look at the "
                "log there")

    def standing_text(self) -> str:
        """The statuses already wrong when the log began, as a clause to append."""
        if not self.standing:
            return ""
        listed = ", ".join(f'"{a.text}"' + (f" ({SEVERITY_WORDS[a.severity]})"
                                             if a.severity in SEVERITY_WORDS else "")
                           for a in self.standing[:SHOWN])
        more = f" and {len(self.standing) - SHOWN} more" if len(self.standing) > SHOWN else ""
        return f"; already so when the log began: {listed}{more}"


def trouble_in_normal_log(name: str, said: AutopilotSaid | None) -> str | None:
    """The warning for a log given as normal in which the autopilot reported trouble while
    it operated (None where it reported none)."""
    if said is None or not said.alarms:
        return None
    return (f"warning: {name}: the autopilot reported trouble while it operated: "
            f"{said.quoted()}: a log given as normal should hold no fault (--healthy keeps "
            "only a log's healthy part)")


def _agreement(named: tuple[str, ...], component: str | None) -> str:
    """Whether the autopilot's thrust-loss check named the part the diagnosis names."""
    if not named or component is None:
        return ""
    if component in named:
        return f": the autopilot's thrust-loss check names {component.replace('_', ' ')} too"
    return (f": the autopilot's thrust-loss check names "
            f"{' and '.join(n.replace('_', ' ') for n in named)}, not "
            f"{component.replace('_', ' ')}")


def _quoted(alarm: SaidAlarm, onset_s: float | None) -> str:
    when = f"at {alarm.first_s:.1f} s"
    if onset_s is not None:
        gap = alarm.first_s - onset_s
        when = (f"{abs(gap):.1f} s {'after' if gap >= 0 else 'before'} the onset "
                f"({alarm.first_s:.1f} s)")
    repeated = f", {alarm.times} times to {alarm.last_s:.1f} s" if alarm.times > 1 else ""
    return f'"{alarm.text}" {when}{repeated}'


def said_while_operating(messages: Sequence[AutopilotMessage], start_ns: int,
                         time_s: np.ndarray, operating: np.ndarray) -> AutopilotSaid | None:
    """The log's messages from while the vehicle operated (``operating`` on the grid
    ``time_s``, seconds from ``start_ns``), or up to `AFTER_OPERATING_S` after; None where
    the log holds none at all (a format without them)."""
    operating_s = time_s[operating] if operating.size == time_s.size else time_s

    def while_operating(at_s: float) -> bool:
        last = np.searchsorted(operating_s, at_s, side="right") - 1
        return bool(last >= 0 and at_s - operating_s[last] <= AFTER_OPERATING_S)

    return said_in(messages, start_ns, while_operating)


def said_in(messages: Sequence[AutopilotMessage], start_ns: int,
            kept: Callable[[float], bool] = lambda _: True) -> AutopilotSaid | None:
    """The messages at the times ``kept`` takes (seconds from ``start_ns``; all by default),
    each text of trouble once with how often it was said; None where there are none."""
    if not messages:
        return None
    alarms: dict[str, SaidAlarm] = {}
    standing: list[SaidAlarm] = []
    others = 0
    for message in sorted(messages, key=lambda m: m.time_ns):
        at_s = (message.time_ns - start_ns) / 1e9
        if message.standing:
            standing.append(SaidAlarm(message.text, message.severity, round(at_s, 3),
                                      round(at_s, 3), 1))
            continue
        if not kept(at_s):
            continue
        if not is_alarm(message):
            others += 1
            continue
        seen = alarms.get(message.text)
        alarms[message.text] = (
            SaidAlarm(message.text, message.severity, round(at_s, 3), round(at_s, 3), 1)
            if seen is None else SaidAlarm(seen.text, seen.severity, seen.first_s,
                                           round(at_s, 3), seen.times + 1))
    return AutopilotSaid(tuple(alarms.values()), others, tuple(standing))
