"""What the vehicle's own software said during a log: ArduPilot's texts (a telemetry log's
STATUSTEXT with its severity, a DataFlash log's MSG records) and the error records it
writes when a check trips (DataFlash ERR: a failsafe, a crash, a thrust loss, a leak), and
PX4's logged messages with their level. Nothing here raises on damaged bytes: a record
that cannot be read says nothing."""

from adapters.autopilot_setup import (
    STATUSTEXT,
    STATUSTEXT_LENGTH,
    TlogPayloads,
    dataflash_records,
    dataflash_text,
    text_of,
)
from adapters.mavlink_scan import RecordIndex
from adapters.signals import AutopilotMessage

# ArduPilot's ERR subsystems (AP_Logger's LogErrorSubsystem), as the report words them.
ERROR_SUBSYSTEMS = {
    1: "main loop", 2: "radio", 3: "compass", 4: "optical flow", 5: "radio failsafe",
    6: "battery failsafe", 7: "GPS failsafe", 8: "ground station failsafe",
    9: "fence failsafe", 10: "flight mode", 11: "GPS", 12: "crash check", 13: "flip",
    14: "autotune", 15: "parachute", 16: "EKF check", 17: "EKF failsafe", 18: "barometer",
    19: "CPU", 20: "ADS-B failsafe", 21: "terrain", 22: "navigation",
    23: "terrain failsafe", 24: "EKF primary", 25: "thrust loss check",
    26: "sensors failsafe", 27: "leak failsafe", 28: "pilot input", 29: "vibration failsafe",
    30: "internal error", 31: "dead-reckoning failsafe"}
# Error codes whose meaning depends on the subsystem (AP_Logger's LogErrorCode).
ERROR_CODES = {(12, 1): "crash", (12, 2): "loss of control", (16, 2): "bad variance",
               (18, 2): "glitch", (18, 3): "bad depth", (11, 2): "glitch",
               (13, 2): "abandoned", (21, 2): "missing terrain data",
               (15, 2): "too low", (15, 3): "landed"}
FAILSAFES = frozenset({5, 6, 7, 8, 9, 17, 20, 23, 25, 26, 27, 29, 31})
ERROR_SEVERITY, CLEARED_SEVERITY = 3, 6        # MAV_SEVERITY_ERROR, MAV_SEVERITY_INFO
ULOG_LEVEL_BASE = ord("0")                     # PX4 writes the level as a digit


def error_text(subsystem: int, code: int) -> str:
    """An ERR record in words: "ERR thrust loss check: occurred"."""
    what = ERROR_SUBSYSTEMS.get(subsystem, f"subsystem {subsystem}")
    if code == 0:
        meaning = "cleared"
    else:
        meaning = ERROR_CODES.get((subsystem, code)) or (
            "occurred" if subsystem in FAILSAFES else "failed to initialise" if code == 1
            else "unhealthy" if code == 4 else f"code {code}")
    return f"ERR {what}: {meaning}"


def dataflash_messages(index: RecordIndex) -> list[AutopilotMessage]:
    """MSG texts and ERR records, in time order; records without a time are left out."""
    texts = [AutopilotMessage(time * 1000, dataflash_text(payload))
             for time, payload in dataflash_records(index, "MSG", "QZ") if time >= 0]
    errors = [AutopilotMessage(time * 1000, error_text(payload[0], payload[1]),
                               CLEARED_SEVERITY if payload[1] == 0 else ERROR_SEVERITY)
              for time, payload in dataflash_records(index, "ERR", "QBB")
              if time >= 0 and len(payload) >= 2]
    return sorted(texts + errors, key=lambda m: m.time_ns)


def tlog_messages(index: RecordIndex) -> list[AutopilotMessage]:
    """Every STATUSTEXT, at its receive time, with its severity."""
    frames = TlogPayloads(index)
    payloads = frames.of(STATUSTEXT, STATUSTEXT_LENGTH)
    return [AutopilotMessage(time * 1000, text_of(raw[1:]), raw[0])
            for time, (_, raw) in zip(frames.times_of(STATUSTEXT), payloads, strict=True)
            if time >= 0]


def ulog_messages(logged: list[tuple[int, str, int]]) -> list[AutopilotMessage]:
    """PX4's logged messages: (µs, text, level as logged: '0' emergency … '7' debug)."""
    return [AutopilotMessage(time_us * 1000, text, _ulog_severity(level))
            for time_us, text, level in logged]


def _ulog_severity(level: int) -> int | None:
    severity = level - ULOG_LEVEL_BASE if level >= ULOG_LEVEL_BASE else level
    return severity if 0 <= severity <= 7 else None

