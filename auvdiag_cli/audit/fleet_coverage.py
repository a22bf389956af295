"""What a fleet's verdicts looked at, per vehicle: a NORMAL on one signal of six says less
than one on all six, and a fleet summary must show which it holds."""

from collections import Counter
from collections.abc import Sequence

from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.engine.coverage import Coverage


def coverage_lines(records: Sequence[AuditRecord]) -> list[str]:
    """Per fleet vehicle: the signals and actuators judged in every log, in some, in none."""
    by_vehicle: dict[str, list[Coverage]] = {}
    for record in records:
        if record.coverage is not None:
            by_vehicle.setdefault(record.fleet_vehicle, []).append(record.coverage)
    lines = []
    for vehicle, coverages in sorted(by_vehicle.items()):
        lines.append(f"{vehicle} ({len(coverages)} logs):")
        for part in ("signals", "actuators"):
            names = list(dict.fromkeys(n for c in coverages for n in getattr(c, part)))
            judged = Counter(n for c in coverages for n in getattr(c, f"{part}_judged"))
            always = [n for n in names if judged[n] == len(coverages)]
            sometimes = [f"{n} ({judged[n]})" for n in names if 0 < judged[n] < len(coverages)]
            never = [n for n in names if not judged[n]]
            lines.append(f"  {part}: judged in every log {len(always)} of {len(names)}"
                         + (f" ({', '.join(always)})" if always else "")
                         + (f"; in some: {', '.join(sometimes)}" if sometimes else "")
                         + (f"; never: {', '.join(never)}" if never else ""))
    return lines
