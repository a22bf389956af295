"""MOOS-IvP `.alog` files as pLogger writes them, laid out by the profile's `[sources.moos]`
table: the `%%` banner with the log's UNIX start, then a line a posting, ``TIME VARIABLE
SOURCE VALUE``, the time in seconds since that start to the millisecond. A signal mapped to
a key of a text posting is written as ``KEY=VALUE`` pairs, one posting for the signals a
variable carries at that time."""

from datetime import UTC, datetime
from pathlib import Path

from adapters.signals import MOOS_VALUE
from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import Record, dive_records
from auvdiag_cli.vehicle.profile import Profile

# The app a posting comes from where the profile's `where` names none.
DEFAULT_SOURCE = "uSimVehicle"
BANNER = "%" * 60


def _posting(record: Record) -> str:
    if record.text is not None:
        return record.text[1]
    values = dict(record.fields)
    if MOOS_VALUE in values:
        return repr(float(values[MOOS_VALUE]))
    return ",".join(f"{key}={float(value)!r}" for key, value in record.fields)


def _line(record: Record, start_ns: int) -> str:
    source = dict(record.where).get("source", DEFAULT_SOURCE)
    return (f"{(record.time_ns - start_ns) / 1e9:.3f} {record.topic} {source} "
            f"{_posting(record)}\n")


def write_alog(dive: SimulatedDive, profile: Profile, path: Path) -> None:
    """The dive as the vehicle's pLogger logs it; segment markers as text postings."""
    opened = datetime.fromtimestamp(dive.start_ns / 1e9, UTC)
    banner = [BANNER, f"%% LOG FILE:       ./{path.name}",
              f"%% FILE OPENED ON  {opened.strftime('%a %b %d %H:%M:%S %Y')}",
              f"%% LOGSTART           {dive.start_ns / 1e9:.3f}", BANNER]
    with path.open("w", encoding="utf-8") as stream:
        stream.write("\n".join(banner) + "\n")
        stream.writelines(_line(record, dive.start_ns)
                          for record in dive_records(dive, profile, "moos"))
