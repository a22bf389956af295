"""Fleet health over time: how close each dive came to its thresholds (the healthy-margin
history), per vehicle and per signal, in the order the dives were made, and a trend test
that flags a vehicle whose margin is shrinking before any dive alarms.

The margin of a dive on a signal is its peak ratio to the threshold: g over the judged
sensors (the largest over the segments), an actuator's extra effort over what its command
relation allows, an actuator's share of its group's effort (its departure from normal over
the threshold, "motor_3 share": a share creeping up over weeks of dives is a thruster
fouling or wearing). 1 is an alarm. The trend test is Mann-Kendall's rank test on a vehicle's
last N dives (one-sided: the ratio rising), with Sen's slope for its size; a signal is
flagged when the test's p-value is below alpha divided by the number of the vehicle's
signals (Bonferroni) and none of those dives alarmed on it. The
vehicle of a log is the one the audit assigned (`audit.fleet_vehicle`: the log's own id,
or by ``--vehicle-from``, else the folder that holds it); its date is the log's own start
time (Unix clock), else the order of the file names."""

import dataclasses
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from auvdiag_cli.audit.fleet_coverage import coverage_lines
from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.audit.store import RESULTS_FOLDER
from auvdiag_errors import UsageError

DEFAULT_LAST = 8
DEFAULT_ALPHA = 0.05
MIN_DIVES = 6          # fewer cannot make p < 0.05 with ties and noise


@dataclass(frozen=True)
class DiveMargin:
    vehicle: str
    log: str
    date: str | None                    # the log's start, ISO 8601 UTC; None: not known
    ratios: dict[str, float]            # signal or actuator -> peak ratio to its threshold


@dataclass(frozen=True)
class SignalTrend:
    vehicle: str
    signal: str
    dives: int
    ratios: tuple[float, ...]           # oldest first
    mann_kendall_s: int
    p_value: float
    sen_slope: float                    # ratio per dive
    alarmed: bool                       # a dive of these reached the threshold
    flagged: bool
    dives_to_threshold: float | None    # at Sen's slope, from the last fitted value

    def describe(self) -> str:
        base = (f"{self.vehicle} {self.signal}: peak/threshold {self.ratios[0]:.2f} -> "
                f"{self.ratios[-1]:.2f} over {self.dives} dives, Mann-Kendall p = "
                f"{self.p_value:.3f}, {self.sen_slope:+.3f} a dive")
        if self.alarmed:
            return base + " (already alarming)"
        if self.flagged:
            left = "" if self.dives_to_threshold is None else (
                "; at this rate the threshold is reached in about "
                f"{self.dives_to_threshold:.0f} dives")
            return base + f": MARGIN SHRINKING{left}"
        return base


@dataclass
class FleetTrend:
    last: int
    alpha: float
    trends: list[SignalTrend] = field(default_factory=list)
    short: dict[str, int] = field(default_factory=dict)     # vehicle -> dives, too few
    coverage: list[str] = field(default_factory=list)       # what was judged, per vehicle

    @property
    def flagged(self) -> list[SignalTrend]:
        return [t for t in self.trends if t.flagged]

    @property
    def flagged_vehicles(self) -> list[str]:
        return sorted({t.vehicle for t in self.flagged})




def margin_history(records: Sequence[AuditRecord]) -> list[DiveMargin]:
    """The analysed dives, oldest first within each vehicle (logs without a date last, by
    name)."""
    dives = [DiveMargin(r.fleet_vehicle, r.log, r.start_time_utc, dict(r.margins))
             for r in records if r.analysed]
    return sorted(dives, key=lambda d: (d.vehicle, d.date is None, d.date or "", d.log))


def mann_kendall(values: Sequence[float]) -> tuple[int, float]:
    """S and the one-sided p-value of an upward trend (normal approximation with the tie
    correction and continuity correction)."""
    n = len(values)
    s = sum((values[j] > values[i]) - (values[j] < values[i])
            for i in range(n) for j in range(i + 1, n))
    ties: dict[float, int] = {}
    for value in values:
        ties[value] = ties.get(value, 0) + 1
    variance = (n * (n - 1) * (2 * n + 5)
                - sum(t * (t - 1) * (2 * t + 5) for t in ties.values())) / 18
    if variance <= 0 or s <= 0:
        return s, 1.0
    z = (s - 1) / math.sqrt(variance)
    return s, 0.5 * math.erfc(z / math.sqrt(2))


def sen_slope(values: Sequence[float]) -> float:
    slopes = sorted((values[j] - values[i]) / (j - i)
                    for i in range(len(values)) for j in range(i + 1, len(values)))
    middle = len(slopes) // 2
    return slopes[middle] if len(slopes) % 2 else 0.5 * (slopes[middle - 1] + slopes[middle])


def _trend(vehicle: str, signal: str, ratios: list[float], alpha: float) -> SignalTrend:
    s, p = mann_kendall(ratios)
    slope = sen_slope(ratios)
    alarmed = max(ratios) >= 1.0
    flagged = p < alpha and slope > 0 and not alarmed
    centre = sorted(r - slope * k for k, r in enumerate(ratios))[len(ratios) // 2]
    fitted_last = centre + slope * (len(ratios) - 1)
    to_go = (1.0 - fitted_last) / slope if slope > 0 and fitted_last < 1.0 else None
    return SignalTrend(vehicle, signal, len(ratios), tuple(round(r, 4) for r in ratios), s,
                       round(p, 5), round(slope, 5), alarmed, flagged,
                       None if to_go is None else round(to_go, 1))


def fleet_trend(records: Sequence[AuditRecord], last: int = DEFAULT_LAST,
                alpha: float = DEFAULT_ALPHA) -> FleetTrend:
    """The trend test over each vehicle's last ``last`` dives, per signal."""
    result = FleetTrend(last, alpha, coverage=coverage_lines(records))
    by_vehicle: dict[str, list[DiveMargin]] = {}
    for dive in margin_history(records):
        by_vehicle.setdefault(dive.vehicle, []).append(dive)
    for vehicle, dives in sorted(by_vehicle.items()):
        recent = dives[-last:]
        if len(recent) < MIN_DIVES:
            result.short[vehicle] = len(recent)
            continue
        series = {signal: [dive.ratios[signal] for dive in recent if signal in dive.ratios]
                  for signal in sorted({name for dive in recent for name in dive.ratios})}
        series = {signal: ratios for signal, ratios in series.items()
                  if len(ratios) >= MIN_DIVES}
        # Bonferroni over the vehicle's signals: a healthy vehicle with many signals is not
        # flagged more often than one with few.
        for signal, ratios in series.items():
            result.trends.append(_trend(vehicle, signal, ratios, alpha / len(series)))
    return result


@dataclass(frozen=True)
class DiveFlag:
    log: str
    date: str | None
    flagged: bool          # the trend test over the dives up to this one flags the vehicle
    alarmed: bool          # this dive's verdict is a fault


def flag_history(records: Sequence[AuditRecord], last: int = DEFAULT_LAST,
                 alpha: float = DEFAULT_ALPHA) -> dict[str, list[DiveFlag]]:
    """For each vehicle, dive by dive: would the trend test have flagged it then (over the
    dives made so far), and did the dive itself alarm."""
    analysed = [r for r in records if r.analysed]
    by_log = {r.log: r for r in analysed}
    history: dict[str, list[DiveFlag]] = {}
    for margin in margin_history(analysed):
        history.setdefault(margin.vehicle, []).append(DiveFlag(
            margin.log, margin.date, False, by_log[margin.log].verdict == "fault"))
    for vehicle, dives in history.items():
        for k, dive in enumerate(dives):
            so_far = fleet_trend([by_log[d.log] for d in dives[:k + 1]], last, alpha)
            dives[k] = dataclasses.replace(dive, flagged=vehicle in so_far.flagged_vehicles)
    return history


def trend_lines(trend: FleetTrend) -> list[str]:
    """The terminal report: the flagged signals first, then every vehicle's."""
    lines = [f"trend test: Mann-Kendall over each vehicle's last {trend.last} dives, "
             f"flagged where p < {trend.alpha:g} and no dive has alarmed yet"]
    if trend.flagged:
        lines.append("margin shrinking:")
        lines += [f"  {t.describe()}" for t in trend.flagged]
    else:
        lines.append("no vehicle's margin is shrinking")
    lines.append("every vehicle and signal:")
    lines += [f"  {t.describe()}" for t in trend.trends if not t.flagged]
    lines += [f"  {vehicle}: only {count} dive(s), at least {MIN_DIVES} are needed"
              for vehicle, count in sorted(trend.short.items())]
    if trend.coverage:
        lines.append("what was judged, per vehicle (margins are over judged signals and "
                     "actuators only):")
        lines += [f"  {line}" for line in trend.coverage]
    return lines


def trend_of_audit(audit_dir: Path, last: int = DEFAULT_LAST,
                   alpha: float = DEFAULT_ALPHA) -> FleetTrend:
    """The trend over the reports an audit wrote into ``audit_dir``."""
    folder = audit_dir / RESULTS_FOLDER
    if not folder.is_dir():
        raise UsageError(f"{audit_dir}: not an audit folder (no {RESULTS_FOLDER}/ in it); "
                         "run 'auvdiag audit ... --output DIR' first")
    records = []
    for path in sorted(folder.glob("*.json")):
        try:
            report = json.loads(path.read_text(encoding="utf-8"))
            if isinstance(report, dict) and "log" in report:
                records.append(AuditRecord.from_report(report))
        except (OSError, ValueError, TypeError, KeyError, AttributeError) as error:
            raise UsageError(f"{path}: not a readable report: {error}") from None
    return fleet_trend(records, last, alpha)
