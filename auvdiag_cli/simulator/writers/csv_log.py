"""CSV logs the way a lab logger writes them, laid out by the profile's `[sources.csv]` table:
a header row, then a row per message with the time and that message's columns filled (the
other cells empty), the clock in the profile's unit."""

import csv
from datetime import UTC, datetime
from pathlib import Path

from auvdiag_cli.simulator.run import SimulatedDive
from auvdiag_cli.simulator.writers.records import dive_records, family_sources
from auvdiag_cli.vehicle.profile import Profile

_PER_SECOND = {"s": 1e9, "ms": 1e6, "us": 1e3, "ns": 1.0}


def _time_text(time_ns: int, unit: str) -> str:
    if unit == "iso":
        return datetime.fromtimestamp(time_ns / 1e9, UTC).isoformat(timespec="microseconds")
    if unit == "hhmmss":
        moment = datetime.fromtimestamp(time_ns // 1_000_000_000, UTC)
        return moment.strftime("%H%M%S")
    if unit == "ns":
        return str(time_ns)
    return f"{time_ns / _PER_SECOND[unit]:.6f}"


def write_csv(dive: SimulatedDive, profile: Profile, path: Path) -> None:
    sources = family_sources(profile, "csv")
    if sources.time is None:
        raise ValueError(f"profile {profile.name!r}: [sources.csv] names no time column")
    signal_columns = {s.field for s in sources.signals.values()}
    if sources.segment is not None:
        signal_columns.add(sources.segment.field)
    columns = [sources.time.column, *sorted(signal_columns)]
    with path.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(columns)
        for record in dive_records(dive, profile, "csv"):
            row = dict.fromkeys(columns, "")
            row[sources.time.column] = _time_text(record.time_ns, sources.time.unit)
            row.update({name: f"{value:.9g}" for name, value in record.fields})
            if record.text is not None:
                row[record.text[0]] = record.text[1]
            writer.writerow(row.values())
