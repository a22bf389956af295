"""The fleet PDF's health-over-time page: each vehicle's margin history (peak ratio to the
threshold per signal, dive by dive in date order), the flagged signals in the alarm colour."""

from collections.abc import Sequence
from typing import TYPE_CHECKING

from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.audit.trend import DiveMargin, FleetTrend, margin_history
from auvdiag_cli.reports.pdf.style import COLOURS, new_page

if TYPE_CHECKING:
    from matplotlib.figure import Figure

VEHICLES_SHOWN = 6


def trend_page(records: Sequence[AuditRecord], trend: FleetTrend) -> "Figure | None":
    """One panel per vehicle (the flagged ones first), or None without dives to show."""
    by_vehicle: dict[str, list[DiveMargin]] = {}
    for dive in margin_history(records):
        by_vehicle.setdefault(dive.vehicle, []).append(dive)
    if not by_vehicle:
        return None
    flagged = {(t.vehicle, t.signal) for t in trend.flagged}
    order = sorted(by_vehicle, key=lambda v: (v not in trend.flagged_vehicles, v))
    shown = order[:VEHICLES_SHOWN]
    from matplotlib.ticker import MaxNLocator

    figure = new_page()
    axes = figure.subplots(len(shown), 1, squeeze=False)[:, 0]
    for ax, vehicle in zip(axes, shown, strict=True):
        dives = by_vehicle[vehicle]
        for signal in sorted({name for dive in dives for name in dive.ratios}):
            points = [(k, dive.ratios[signal]) for k, dive in enumerate(dives)
                      if signal in dive.ratios]
            is_flagged = (vehicle, signal) in flagged
            ax.plot([k for k, _ in points], [r for _, r in points], marker=".", lw=1.6
                    if is_flagged else 0.7, color=COLOURS["fault"] if is_flagged else None,
                    label=signal + (" (shrinking)" if is_flagged else ""))
        ax.axhline(1.0, color=COLOURS["threshold"], ls="--", lw=0.8)
        ax.set_ylabel("peak / threshold", fontsize=7)
        ax.set_title(f"{vehicle}: {len(dives)} dives, oldest first", fontsize=8, loc="left")
        ax.tick_params(labelsize=6)
        if ax.get_lines()[:-1]:           # the signals drawn (the last line: the threshold)
            ax.legend(fontsize=5, loc="upper left", ncols=3)
    for ax in axes:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes[-1].set_xlabel("dive (oldest first)", fontsize=7)
    figure.suptitle(f"Health over time (trend test over the last {trend.last} dives; "
                    f"{len(order) - len(shown)} more vehicles not drawn)"
                    if len(order) > len(shown) else
                    f"Health over time (trend test over the last {trend.last} dives)",
                    fontsize=9)
    return figure
