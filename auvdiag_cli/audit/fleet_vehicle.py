"""Which vehicle of the fleet each log belongs to, for the trend and the fleet PDF: the log's
own word where it names a vehicle (`adapters.identity`), else the rule `--vehicle-from`
gives: the folder holding the log, a regular expression on its name, or a CSV mapping."""

import csv
import re
from collections.abc import Collection
from dataclasses import dataclass, field, replace
from pathlib import Path

from adapters import LogSources, detect_format
from adapters.identity import log_identity
from auvdiag_errors import AuvdiagError, UsageError

RULES = "log, folder, regex:PATTERN or csv:FILE"


@dataclass(frozen=True)
class FleetVehicle:
    vehicle: str
    source: str        # how it was found: "log: HEARTBEAT …", "folder", "regex", "csv"


@dataclass(frozen=True)
class VehicleRule:
    """``log`` (the default): the log's own identity, else its folder; ``folder``: always
    the folder; ``regex:PATTERN``: the first group (or the whole match) of PATTERN searched
    in the log's file name, else the folder; ``csv:FILE``: FILE's rows ``log,vehicle``
    (a file name or a path), else the folder."""

    kind: str = "log"
    pattern: re.Pattern[str] | None = None
    mapping: dict[str, str] = field(default_factory=dict)
    ros_topics: frozenset[str] = frozenset()
    namespace: str | None = None

    @classmethod
    def parse(cls, text: str, ros: LogSources | None = None) -> "VehicleRule":
        """``ros``: the profile's ROS sources, whose namespace names a ROS log's vehicle."""
        rule = cls._parsed(text)
        if ros is None:
            return rule
        return replace(rule, ros_topics=frozenset(ros.topics), namespace=ros.namespace)

    @classmethod
    def _parsed(cls, text: str) -> "VehicleRule":
        kind, _, argument = text.partition(":")
        if kind in ("log", "folder") and not argument:
            return cls(kind)
        if kind == "regex" and argument:
            try:
                return cls(kind, pattern=re.compile(argument))
            except re.error as error:
                raise UsageError(f"--vehicle-from {text!r}: not a regular expression: "
                                 f"{error}") from None
        if kind == "csv" and argument:
            return cls(kind, mapping=_read_mapping(Path(argument)))
        raise UsageError(f"--vehicle-from {text!r}: expected {RULES}")

    def vehicle_of(self, log: Path) -> FleetVehicle:
        if self.kind == "log":
            said = _identity(log, self.ros_topics, self.namespace)
            if said is not None:
                return said
        elif self.kind == "regex" and self.pattern is not None:
            found = self.pattern.search(log.name)
            if found:
                return FleetVehicle(found.group(1) if found.groups() else found.group(0),
                                    "regex")
        elif self.kind == "csv":
            named = self.mapping.get(str(log)) or self.mapping.get(log.name)
            if named:
                return FleetVehicle(named, "csv")
        return FleetVehicle(log.parent.name or ".", "folder")


def _identity(log: Path, ros_topics: Collection[str], namespace: str | None
              ) -> FleetVehicle | None:
    try:
        said = log_identity(log, detect_format(log), ros_topics, namespace)
    except AuvdiagError:
        return None
    return None if said is None or not said.distinctive else FleetVehicle(
        said.vehicle, f"log: {said.evidence}")


def _read_mapping(path: Path) -> dict[str, str]:
    try:
        with path.open(encoding="utf-8", newline="") as stream:
            rows = [row for row in csv.reader(stream) if row and not row[0].startswith("#")]
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise UsageError(f"{path}: cannot read the vehicle mapping: {error}") from None
    if rows and [c.strip().lower() for c in rows[0][:2]] == ["log", "vehicle"]:
        rows = rows[1:]
    bad = [n for n, row in enumerate(rows, 1) if len(row) < 2 or not row[1].strip()]
    if bad or not rows:
        raise UsageError(f"{path}: a vehicle mapping needs rows 'log,vehicle'"
                         + (f" (row {bad[0]} is not)" if bad else " (it has none)"))
    return {row[0].strip(): row[1].strip() for row in rows}
