"""The time-history pages of a dive report. Every page shares the time axis, the onset and
detection markers and the shading of the Diagnosis Motion Sequences."""

from typing import TYPE_CHECKING, Any

import numpy as np

from auvdiag_cli.engine.effort_words import rise_range
from auvdiag_cli.reports.pdf.style import COLOURS, COMMAND_CYCLE, new_page, seconds_label
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.series import Series

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _names(series: Series, key: str) -> list[str]:
    return [str(name) for name in series[key]]


def _mark_events(ax: "Axes", report: Report, label: bool) -> None:
    for segment in report.segments:
        if segment.mode == "routine":
            ax.axvspan(segment.start_s, segment.end_s, color=COLOURS["dms"], alpha=0.18, lw=0)
            ax.axvline(segment.start_s, color=COLOURS["dms"], lw=0.6)
    for at, colour, text in ((report.onset_s, COLOURS["onset"], "onset"),
                             (report.detected_at_s, COLOURS["alarm"], "detected")):
        if at is not None:
            ax.axvline(at, color=colour, ls="--", lw=1.0, label=text if label else None)
    said = report.autopilot.alarms if report.autopilot is not None else ()
    for number, alarm in enumerate(said):
        ax.axvline(alarm.first_s, color=COLOURS["autopilot"], ls=":", lw=1.0,
                   label="the autopilot reported trouble" if label and not number else None)


def _figure_legend(figure: "Figure", axes: list["Axes"]) -> None:
    """One legend under the plots (never over the data), each label once."""
    entries: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    figure.legend(list(entries.values()), list(entries), loc="outside lower center",
                  ncols=min(len(entries), 7))


def _stacked(report: Report, rows: int, title: str) -> tuple["Figure", list["Axes"]]:
    figure = new_page()
    axes = list(np.atleast_1d(figure.subplots(rows, 1, sharex=True)))
    axes[0].set_title(title, loc="left", fontweight="bold")
    axes[-1].set_xlabel(seconds_label())
    for ax in axes:
        _mark_events(ax, report, label=ax is axes[0])
    return figure, axes


# From this many panels on a page, each is too short for its label written upright.
UPRIGHT_LABEL_ROWS = 5


def _label(ax: "Axes", text: str, rows: int, **style: Any) -> None:
    """A panel's y label: upright beside a tall panel; across, the unit under the name,
    beside a short one (written upright it would run into the panels above and below)."""
    if rows < UPRIGHT_LABEL_ROWS:
        ax.set_ylabel(text, **style)
    else:
        ax.set_ylabel(text.replace(" [", "\n["), rotation=0, ha="right", va="center",
                      fontsize=8, **style)


def _has_dms(report: Report) -> bool:
    """Whether the log holds Diagnosis Motion Sequences (shaded on every page)."""
    return any(segment.mode == "routine" for segment in report.segments)


def _with_dms(report: Report, title: str) -> str:
    """``title`` with a word on the shading where the log has Diagnosis Motion Sequences."""
    return f"{title}; shaded: Diagnosis Motion Sequences" if _has_dms(report) else title


def sensors_page(report: Report, series: Series) -> "Figure":
    names, units = _names(series, "sensor_names"), report.units
    figure, axes = _stacked(report, len(names), _with_dms(
        report, "Sensors (SS) and the model of the healthy vehicle (SM)"))
    t = series["time_s"]
    for i, (ax, name) in enumerate(zip(axes, names, strict=True)):
        ax.plot(t, series["measured"][:, i], color=COLOURS["measured"], lw=0.8,
                label="sensor SS")
        ax.plot(t, series["modelled"][:, i], color=COLOURS["modelled"], lw=0.8,
                label="model SM")
        _label(ax, f"{name} [{units.get(name, '?')}]", len(axes))
    _figure_legend(figure, axes)
    return figure


def residual_page(report: Report, series: Series) -> "Figure | None":
    """g per signal against its threshold, b shaded; none where the replay judges no signal
    (every one left to the change test, or none it can predict): its page would show only
    greyed curves that raise nothing."""
    names = _names(series, "sensor_names")
    if all(name in report.not_judged for name in names):
        return None
    figure, axes = _stacked(report, len(names),
                            "Residual index g (percent of full scale) against its threshold; "
                            "red band: b = 1")
    t = series["time_s"]
    not_judged = report.not_judged
    for i, (ax, name) in enumerate(zip(axes, names, strict=True)):
        if name in not_judged:      # drawn, greyed: it raises no alarm
            ax.plot(t, series["g_percent"][:, i], color=COLOURS["dms"], lw=0.8)
            _label(ax, f"g {name} [%] (not judged)", len(axes), color=COLOURS["muted"])
            ax.set_ylim(bottom=0)
            continue
        ax.plot(t, series["g_percent"][:, i], color=COLOURS["measured"], lw=0.8, label="g")
        ax.step(t, series["thresholds"][:, i], where="post", color=COLOURS["threshold"],
                lw=1.0, ls=":", label="threshold")
        ax.fill_between(t, 0, 1, where=series["b"][:, i] > 0, step="post",
                        color=COLOURS["alarm"], alpha=0.25, lw=0,
                        transform=ax.get_xaxis_transform(), label="b = 1")
        _label(ax, f"g {name} [%]", len(axes))
        ax.set_ylim(bottom=0)
    _figure_legend(figure, axes)
    return figure


# The failure's effect is drawn from this long before the onset to this long after the
# healthy vehicle's replay from it ends: what came before, and where the two part.
EFFECT_MARGIN_S = 10.0


def effect_page(report: Report, series: Series) -> "Figure | None":
    """The failure's effect, close up: each signal the model predicts, as the vehicle read
    it and as the model of the healthy vehicle, replayed from the onset, says it would
    have (`engine.failure_effect`)."""
    healthy = series.get("healthy_from_onset")
    if healthy is None:
        return None
    drawn = [i for i in range(healthy.shape[1]) if np.isfinite(healthy[:, i]).any()]
    if not drawn:
        return None
    t, names = series["time_s"], _names(series, "sensor_names")
    replayed = t[np.isfinite(healthy[:, drawn]).any(axis=1)]
    shown = (t >= replayed[0] - EFFECT_MARGIN_S) & (t <= replayed[-1] + EFFECT_MARGIN_S)
    figure, axes = _stacked(report, len(drawn),
                            "The failure's effect: the vehicle (SS) against the model of the "
                            "healthy vehicle replayed from the onset")
    for ax, i in zip(axes, drawn, strict=True):
        ax.plot(t[shown], series["measured"][shown, i], color=COLOURS["measured"], lw=0.9,
                label="sensor SS")
        ax.plot(t[shown], healthy[shown, i], color=COLOURS["healthy"], lw=1.4, ls="--",
                label="the healthy vehicle from the onset")
        _label(ax, f"{names[i]} [{report.units.get(names[i], '?')}]", len(axes))
    axes[0].set_xlim(t[shown][0], t[shown][-1])     # the shaded sequences reach further
    _figure_legend(figure, axes)
    return figure


def change_page(report: Report, series: Series) -> "Figure | None":
    """The change test: each signal it judges against the log's own beginning, its
    statistic over its threshold (1: the threshold), step by step."""
    if "change_ratio" not in series or report.change_check is None:
        return None
    names = _names(series, "change_names")
    figure, axes = _stacked(report, len(names),
                            "Against the log's own beginning: each signal's change "
                            "statistic over its threshold")
    t, ratios = series["time_s"], series["change_ratio"]
    start = report.change_check.judged_from_s
    for i, (ax, name) in enumerate(zip(axes, names, strict=True)):
        if start is not None:
            ax.axvspan(t[0], start, color=COLOURS["dms"], alpha=0.12, lw=0,
                       label="its reference, not judged")
        ax.plot(t, ratios[:, i], color=COLOURS["measured"], lw=0.8, label="over its threshold")
        ax.axhline(1.0, color=COLOURS["threshold"], lw=1.0, ls=":", label="threshold")
        with np.errstate(invalid="ignore"):
            over = ratios[:, i] > 1.0
        ax.fill_between(t, 0, 1, where=over, step="post", color=COLOURS["alarm"], alpha=0.25,
                        lw=0, transform=ax.get_xaxis_transform(), label="over")
        _label(ax, name, len(axes))
        ax.set_ylim(bottom=0)
    _figure_legend(figure, axes)
    return figure


def commands_page(report: Report, series: Series) -> "Figure":
    figure, axes = _stacked(report, 1, "Commands, with the Diagnosis Motion Sequences"
                            if _has_dms(report) else "Commands")
    ax, t = axes[0], series["time_s"]
    for i, name in enumerate(_names(series, "command_names")):
        ax.plot(t, series["commands"][:, i], lw=0.9, label=name,
                color=COMMAND_CYCLE[i % len(COMMAND_CYCLE)])
    units = {report.units.get(name) for name in _names(series, "command_names")}
    unit = units.pop() if len(units) == 1 else None
    ax.set_ylabel("command (normalised, full scale = 1)" if unit is None else f"command [{unit}]")
    for segment in report.segments:
        if segment.mode == "routine":
            ax.annotate(segment.name, ((segment.start_s + segment.end_s) / 2, 0.98),
                        xycoords=("data", "axes fraction"), ha="center", va="top",
                        fontsize=8, color=COLOURS["muted"], annotation_clip=True,
                        bbox={"facecolor": "white", "edgecolor": "none", "pad": 1.0})
    _figure_legend(figure, axes)
    return figure


def effort_page(report: Report, series: Series) -> "Figure | None":
    """Each actuator's share of its group's effort, window by window, against the normal
    share for the same conditions (dashed) and its band of ± one window's spread."""
    groups = [str(g) for g in series.get("effort_groups", [])]
    if not groups:
        return None
    shares = {} if report.actuators is None else report.actuators.shares
    figure, axes = _stacked(report, len(groups),
                            "Share of the group's effort per actuator (1 = the group's mean); "
                            "dashed: normal share, band: ± one window's normal spread")
    for k, (ax, group) in enumerate(zip(axes, groups, strict=True)):
        t = series[f"effort_{k}_time_s"]
        for i, name in enumerate(_names(series, f"effort_{k}_members")):
            colour = COMMAND_CYCLE[i % len(COMMAND_CYCLE)]
            harder = name in shares and shares[name].driven_harder
            normal = series[f"effort_{k}_normal"][:, i]
            band = float(series[f"effort_{k}_band"][i])
            ax.fill_between(t, normal - band, normal + band, color=colour, alpha=0.12, lw=0)
            ax.plot(t, normal, color=colour, lw=0.8, ls="--")
            ax.plot(t, series[f"effort_{k}_shares"][:, i], color=colour, marker=".",
                    lw=2.2 if harder else 1.0,
                    label=f"{name} (driven harder)" if harder else name)
        ax.set_ylabel(f"share of {group}")
        rises = [a.smallest_rise_shown for a in shares.values()
                 if a.group == group and a.smallest_rise_shown is not None]
        if rises:
            ax.text(0.01, 0.97, f"one weak actuator shows over this log from "
                    f"+{rise_range(rises)}", transform=ax.transAxes, va="top", fontsize=7,
                    bbox={"facecolor": "white", "edgecolor": "none", "pad": 1.0})
    _figure_legend(figure, axes)
    return figure


def substitution_page(report: Report, series: Series) -> "Figure | None":
    substitution = report.substitution
    if substitution is None or "substituted" not in series:
        return None
    figure = new_page()
    signal_ax, map_ax = figure.subplots(1, 2, width_ratios=[1.4, 1.0])
    signal = substitution.signal
    column = _names(series, "sensor_names").index(signal)
    t = series["time_s"]
    signal_ax.set_title(f"Substituting Control: the model's {signal} replaces the failed "
                        "sensor", loc="left", fontweight="bold")
    _mark_events(signal_ax, report, label=True)
    signal_ax.plot(t, series["measured"][:, column], color=COLOURS["measured"], lw=0.8,
                   label="failed sensor")
    signal_ax.plot(t, series["substituted"], color=COLOURS["modelled"], lw=0.9,
                   label="used signal (model after onset)")
    if "substituted_truth" in series:
        signal_ax.plot(t, series["substituted_truth"], color=COLOURS["truth"], lw=0.8,
                       ls="--", label="truth")
    signal_ax.set_xlabel(seconds_label())
    signal_ax.set_ylabel(f"{signal} [{substitution.unit}]")
    _draw_tracks(map_ax, series)
    _figure_legend(figure, [signal_ax, map_ax])
    return figure


TRACKS = (("track_truth_m", "truth", COLOURS["truth"], "--"),
          ("track_failed_m", "dead-reckoned, failed sensor", COLOURS["measured"], "-"),
          ("track_substituted_m", "dead-reckoned, substitute", COLOURS["modelled"], "-"),
          ("closed_loop_m", "closed-loop replay (model as plant)", COLOURS["closed_loop"], "-."))


def _draw_tracks(ax: "Axes", series: Series) -> None:
    """North (x) up, east (y) to the right, as on a chart."""
    ax.set_title("Tracks", loc="left", fontweight="bold")
    drawn = False
    for key, label, colour, style in TRACKS:
        if key in series:
            ax.plot(series[key][:, 1], series[key][:, 0], color=colour, ls=style, lw=1.0,
                    label=label)
            drawn = True
    if "waypoints_m" in series:
        ax.plot(series["waypoints_m"][:, 1], series["waypoints_m"][:, 0], "s", ms=4,
                color=COLOURS["text"], label="waypoints")
        drawn = True
    if not drawn:
        ax.text(0.5, 0.5, "no navigation signals to dead-reckon", ha="center",
                transform=ax.transAxes, color=COLOURS["muted"])
        return
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
