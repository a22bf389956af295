"""What a fleet's verdicts looked at, per vehicle: a NORMAL on one signal of six says less
than one on all six, and a fleet summary must show which it holds."""

from collections import Counter
from collections.abc import Callable, Sequence
from typing import Any


def coverage_lines(records: Sequence[dict[str, Any]],
                   vehicle_of: Callable[[dict[str, Any]], str]) -> list[str]:
    """Per vehicle (as ``vehicle_of`` a report says): the signals and actuators judged in
    every log, in some, in none."""
    by_vehicle: dict[str, list[dict[str, Any]]] = {}
    for record in records:
        if record.get("coverage"):
            by_vehicle.setdefault(vehicle_of(record), []).append(record["coverage"])
    lines = []
    for vehicle, coverages in sorted(by_vehicle.items()):
        lines.append(f"{vehicle} ({len(coverages)} logs):")
        for part in ("signals", "actuators"):
            names = list(dict.fromkeys(n for c in coverages for key in ("judged", "not_judged")
                                       for n in c[part][key]))
            judged = Counter(n for c in coverages for n in c[part]["judged"])
            always = [n for n in names if judged[n] == len(coverages)]
            sometimes = [f"{n} ({judged[n]})" for n in names if 0 < judged[n] < len(coverages)]
            never = [n for n in names if not judged[n]]
            lines.append(f"  {part}: judged in every log {len(always)} of {len(names)}"
                         + (f" ({', '.join(always)})" if always else "")
                         + (f"; in some: {', '.join(sometimes)}" if sometimes else "")
                         + (f"; never: {', '.join(never)}" if never else ""))
    return lines
