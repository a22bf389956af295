"""A log's clock against a UTC time it carries.

A companion computer without a real-time clock or a network (a Jetson on a field, say)
stamps its log with whatever time it booted with, days or years off; the autopilot's GPS
time, which such a log often carries (mavros ``time_reference``), is not. Four of ALFA's
30 sequences of 2018-07-30 were recorded 9.8 days behind it, and read as flights of
2018-07-21. Where a profile names such a time (`adapters.signals.CLOCK_REFERENCE`) and the
log's clock is off from it by more than `TOLERANCE_S`, the UTC times a report gives (its
start, onset and detection, and the day its calibration logs were recorded) are set by
it; times in seconds keep counting on the log's own clock, which `--healthy` and the
MCAP export share.
"""

import numpy as np

from adapters.signals import CLOCK_REFERENCE, Signals

# A clock this close to the reference is taken as it is: the reference's own latency and
# a resolution of a second (a time's seconds alone) are well within it.
TOLERANCE_S = 60.0
# Epoch times in seconds, milliseconds, microseconds and nanoseconds, told apart by size:
# the smallest value of each that is a date after 1973.
EPOCH_UNITS_NS = ((1e17, 1), (1e14, 10**3), (1e11, 10**6), (1e8, 10**9))


def utc_offset_ns(signals: Signals) -> int:
    """The UTC time the log carries less its own clock, in whole seconds (ns); 0 where it
    carries none, or its clock is within TOLERANCE_S of it."""
    series = signals.series.get(CLOCK_REFERENCE)
    if series is None or not len(series):
        return 0
    values = np.asarray(series.values, float)
    typical = float(np.nanmedian(values)) if np.isfinite(values).any() else 0.0
    unit = next((ns for smallest, ns in EPOCH_UNITS_NS if typical >= smallest), None)
    if unit is None:      # not a time since 1970
        return 0
    offset_s = float(np.nanmedian(values * (unit / 1e9) - series.times_ns / 1e9))
    return 0 if abs(offset_s) <= TOLERANCE_S else round(offset_s) * 10**9


def utc_start_ns(signals: Signals) -> int:
    """The log's start in UTC: its clock's, set by the UTC time it carries where off."""
    return signals.start_ns + utc_offset_ns(signals)


def clock_gap(offset_ns: int) -> str | None:
    """How far the log's clock is off from the UTC time it carries (None: it is not)."""
    if not offset_ns:
        return None
    days = abs(offset_ns) / 86400e9
    how_far = f"{days:.1f} days" if days >= 1 else f"{abs(offset_ns) / 3600e9:.1f} hours"
    return (f"the log's clock runs {how_far} {'behind' if offset_ns > 0 else 'ahead of'} the "
            "UTC time it carries (the profile's clock_reference)")


def clock_note(offset_ns: int) -> list[str]:
    """What a report says of a log whose clock is off from the UTC time it carries."""
    gap = clock_gap(offset_ns)
    return [] if gap is None else [f"{gap}: its UTC times here are set by that time, to the "
                                   "second; times in seconds count on the log's own clock"]
