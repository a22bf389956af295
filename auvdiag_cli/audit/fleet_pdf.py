"""The fleet summary of an audit: totals, problem logs and the trend test in words, then
verdicts by vehicle and date, faults by component, a timeline, the worst g of each log, and
each vehicle's margin history."""

from collections import Counter
from collections.abc import Sequence
from datetime import timedelta
from pathlib import Path
from typing import TYPE_CHECKING

from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.audit.trend import FleetTrend, fleet_trend, trend_lines
from auvdiag_cli.audit.trend_pdf import trend_page
from auvdiag_cli.reports.pdf.style import COLOURS, new_page, pdf_document
from auvdiag_cli.reports.pdf.text import (
    Line,
    heading,
    paragraph,
    text_height,
    text_page,
    write_text_pages,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

VERDICTS = ("normal", "partial", "fault", "undetermined", "error")
LABELS = {"partial": "normal, part judged"}
WORST_SHOWN = 30
TIMELINE_MIN_SPAN = timedelta(hours=1)    # a timeline of logs closer in time than this
TEXT_ABOVE_CHARTS = 0.4    # of the page: a summary this short shares its page with the charts


def _verdict(row: AuditRecord) -> str:
    """The verdict, with "partial" for a NORMAL over less than the whole vehicle or log."""
    if row.error:
        return "error"
    if row.partly_judged:
        return "partial"
    return str(row.verdict)


def summary_lines(rows: Sequence[AuditRecord], skipped: Sequence[tuple[Path, str]],
                  companions: int, interrupted: bool) -> list[Line]:
    counts = Counter(_verdict(r) for r in rows)
    partly = f" and {counts['partial']} normal judged in part" if counts["partial"] else ""
    lines = paragraph(f"{len(rows)} logs: {counts['normal']} normal{partly}, {counts['fault']} "
                      f"with a fault, {counts['undetermined']} undetermined, {counts['error']} "
                      "not analysable", size=14, bold=True)
    if companions:
        lines += paragraph(f"{companions} files named after a log beside it (truth, mission "
                           "plans, reports) were left alone.", colour=COLOURS["muted"])
    if interrupted:
        lines += paragraph("The audit was interrupted: this summary covers the logs finished "
                           "so far; run the same command again to finish.",
                           colour=COLOURS["fault"], bold=True)
    faults = [r for r in rows if _verdict(r) == "fault"]
    if faults:
        lines += heading("Faults")
        for r in faults:
            what = r.component or " or ".join(r.candidates) or "unidentified"
            when = "" if r.onset_s is None else f", onset {r.onset_s:.1f} s"
            lines += paragraph(f"{Path(r.log).name}: {what}{when}", family="monospace",
                               size=8.5)
    unseen = [r for r in rows if r.autopilot_alarms and _verdict(r) != "fault"]
    if unseen:
        lines += heading("Trouble the autopilot reported that the diagnosis did not find")
        for r in unseen:
            lines += paragraph(f"{Path(r.log).name} ({_verdict(r)}): "
                               + "; ".join(r.autopilot_alarms), family="monospace", size=8.5)
    errors = [r for r in rows if r.error]
    if errors:
        lines += heading("Logs that could not be analysed")
        for r in errors:
            lines += paragraph(f"{Path(r.log).name}: {r.error}", family="monospace",
                               size=8.5)
    if skipped:
        lines += heading(f"Skipped: {len(skipped)} files that are not logs, or copies of one")
        for path, reason in skipped:
            lines += paragraph(f"{path}: {reason}", family="monospace", size=8.5,
                               colour=COLOURS["muted"])
    return lines


def _vehicle_and_date(row: AuditRecord) -> tuple[str, str]:
    vehicle = row.fleet_vehicle or ("not analysable" if row.error else "?")
    return vehicle, (row.start_time_utc or "no clock")[:10]


def _by_vehicle_and_date(ax: "Axes", rows: Sequence[AuditRecord]) -> None:
    from matplotlib.ticker import MaxNLocator

    groups = sorted({_vehicle_and_date(r) for r in rows})
    labels = [f"{vehicle}\n{date}" for vehicle, date in groups]
    bottom = [0] * len(groups)
    for verdict in VERDICTS:
        heights = [sum(1 for r in rows if _verdict(r) == verdict and _vehicle_and_date(r) == g)
                   for g in groups]
        if not any(heights):
            continue        # a verdict no log got: not in the legend either
        ax.bar(labels, heights, bottom=bottom, color=COLOURS[verdict],
               label=LABELS.get(verdict, verdict))
        bottom = [b + h for b, h in zip(bottom, heights, strict=True)]
    ax.set_title("Verdicts by vehicle and date", loc="left", fontweight="bold")
    ax.set_ylabel("logs")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.tick_params(axis="x", labelsize=7, labelrotation=30)
    # Beside the bars, not over the tallest of them.
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7)


def _faults_by_component(ax: "Axes", rows: Sequence[AuditRecord]) -> None:
    from matplotlib.ticker import MaxNLocator

    named = Counter(r.component or "not isolated" for r in rows if _verdict(r) == "fault")
    ax.set_title("Faults by component", loc="left", fontweight="bold")
    if not named:
        ax.text(0.5, 0.5, "no fault found", ha="center", va="center", transform=ax.transAxes,
                color=COLOURS["muted"])
        ax.set_axis_off()
        return
    names = sorted(named, key=lambda n: (-named[n], n))
    ax.barh(names, [named[n] for n in names], color=COLOURS["fault"])
    ax.invert_yaxis()
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("logs")


def _timeline(ax: "Axes", rows: Sequence[AuditRecord]) -> None:
    """Each log at its start time (or its place in the list, for logs without a clock)."""
    import matplotlib.dates as mdates
    import pandas as pd

    dated = all(r.start_time_utc for r in rows)
    vehicles = sorted({_vehicle_and_date(r)[0] for r in rows})
    for verdict in VERDICTS:
        chosen = [(i, r) for i, r in enumerate(rows) if _verdict(r) == verdict]
        if not chosen:
            continue
        x = ([pd.Timestamp(r.start_time_utc).to_pydatetime() for _, r in chosen] if dated
             else [i for i, _ in chosen])
        y = [vehicles.index(_vehicle_and_date(r)[0]) for _, r in chosen]
        ax.scatter(x, y, color=COLOURS[verdict], s=18, label=LABELS.get(verdict, verdict),
                   zorder=3)
    ax.set_yticks(range(len(vehicles)), vehicles)
    ax.set_ylim(-0.5, len(vehicles) - 0.5)
    ax.set_title("Timeline", loc="left", fontweight="bold")
    if dated:
        starts = [pd.Timestamp(r.start_time_utc).to_pydatetime() for r in rows]
        # Logs that all start within minutes (or at one time) would get matplotlib's
        # two-year margin either side of a date axis with no span.
        middle, span = min(starts) + (max(starts) - min(starts)) / 2, max(starts) - min(starts)
        half = max(span * 0.55, TIMELINE_MIN_SPAN / 2)
        ax.set_xlim(middle - half, middle + half)
        locator = mdates.AutoDateLocator()
        ax.xaxis.set_major_locator(locator)
        ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))
        ax.set_xlabel("log start (UTC)")
    else:
        ax.set_xlabel("log (in table order; not every log has a clock)")


def _worst_g(ax: "Axes", rows: Sequence[AuditRecord]) -> None:
    from matplotlib.ticker import NullFormatter

    ranked = sorted((r for r in rows if r.worst_g_ratio is not None),
                    key=lambda r: -(r.worst_g_ratio or 0.0))[:WORST_SHOWN]
    shown = f" (the {WORST_SHOWN} highest)" if len(ranked) == WORST_SHOWN else ""
    ax.set_title(f"Worst g per log, over its threshold{shown}", loc="left", fontweight="bold")
    if not ranked:
        ax.text(0.5, 0.5, "no log has a signal the replay judges", ha="center", va="center",
                transform=ax.transAxes, color=COLOURS["muted"])
        ax.set_axis_off()
        return
    names = [Path(r.log).name for r in ranked]
    ax.barh(names, [r.worst_g_ratio or 0.0 for r in ranked],
            color=[COLOURS[_verdict(r)] for r in ranked])
    ax.axvline(1.0, color=COLOURS["threshold"], ls=":", lw=1.0)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())     # the minor labels run into each other
    ax.set_xlabel("largest g / threshold (1 = alarm level)")
    ax.tick_params(axis="y", labelsize=max(4, 8 - len(ranked) // 10))


def charts_page(rows: Sequence[AuditRecord], figure: "Figure | None" = None,
                top: float = 0.93) -> "Figure":
    """The four charts, on a page of their own or below the text already on ``figure``
    (from ``top`` down)."""
    page = figure or new_page()
    area = (page if figure is None else
            page.subfigures(2, 1, height_ratios=[1 - top, top], squeeze=False)[1, 0])
    grid = area.subplots(2, 2)
    _by_vehicle_and_date(grid[0][0], rows)
    _faults_by_component(grid[0][1], rows)
    _timeline(grid[1][0], rows)
    _worst_g(grid[1][1], rows)
    return page


def _trend_text(trend: FleetTrend) -> list[Line]:
    """The trend test's lines, indented as the terminal shows them."""
    text = heading("Health over time")
    for line in trend_lines(trend):
        depth = (len(line) - len(line.lstrip())) / 2
        text += paragraph(line.strip(), size=9, indent=0.02 * depth,
                          colour=COLOURS["fault"] if "SHRINKING" in line else COLOURS["text"])
    return text


def render_fleet_report(records: Sequence[AuditRecord], skipped: Sequence[tuple[Path, str]],
                        target: Path, companions: int = 0, interrupted: bool = False) -> int:
    rows = sorted(records, key=lambda r: r.log)
    title = "auvdiag fleet audit"
    trend = fleet_trend(records)
    text = summary_lines(rows, skipped, companions, interrupted) + _trend_text(trend)
    with pdf_document(target, title, f"Audit of {len(rows)} logs") as pdf:
        if rows and text_height(text) <= TEXT_ABOVE_CHARTS:
            # A short summary shares its page with the charts, not an empty page's top.
            figure, bottom = text_page(text, title, "Fleet audit")
            pdf.savefig(charts_page(rows, figure, bottom - 0.03))
            pages = 1
        else:
            pages = write_text_pages(pdf, text, title, "Fleet audit")
            if rows:
                figure = charts_page(rows)
                figure.suptitle(title, x=0.99, ha="right", fontsize=8,
                                color=COLOURS["muted"])
                pdf.savefig(figure)
                pages += 1
        health = trend_page(records, trend)
        if health is not None:
            pdf.savefig(health)
            pages += 1
    return pages
