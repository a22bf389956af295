"""The PDF report of one dive, drawn from the report and its time histories only (so a
saved report can be drawn again without the log or the model)."""

from collections.abc import Mapping
from pathlib import Path

from auvdiag_cli.reports.json_report import verdict_title
from auvdiag_cli.reports.pdf.facts import assumption_remarks, summary_facts
from auvdiag_cli.reports.pdf.plots import (
    change_page,
    commands_page,
    effect_page,
    effort_page,
    residual_page,
    sensors_page,
    substitution_page,
)
from auvdiag_cli.reports.pdf.style import COLOURS, pdf_document
from auvdiag_cli.reports.pdf.text import Line, columns, heading, paragraph, write_text_pages
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.series import Series


def _banner(report: Report) -> Line:
    verdict = report.verdict
    partial = verdict == "normal" and report.coverage is not None and \
        not report.coverage.complete
    colour = COLOURS["partial"] if partial else COLOURS.get(verdict, COLOURS["error"])
    return Line(verdict_title(report), size=20, bold=True, banner=colour)


def partial_log_text(report: Report) -> str | None:
    """"PARTIAL LOG: ..." when the report covers only the readable part of a damaged log."""
    completeness = report.completeness
    if completeness is None or completeness.status != "partial":
        return None
    read, at = completeness.seconds_read, completeness.damage_at_byte
    where = f" (damage at byte {at} of {completeness.bytes_total})" if at else ""
    span = f" the first {read:.1f} s" if read is not None else " part"
    return f"PARTIAL LOG: only{span} could be read{where}"


def first_page_lines(report: Report, series: Series | None) -> list[Line]:
    lines = [_banner(report)]
    partial = partial_log_text(report)
    if partial is not None:
        lines.append(Line(partial, size=13, bold=True, banner=COLOURS["error"]))
    lines.append(Line(""))
    for label, value in summary_facts(report):
        lines += paragraph(f"{label}:  {value}", size=10)
    lines += heading("The paper's assumptions, and what they mean for this log")
    for number, (assumption, remark) in enumerate(assumption_remarks(report, series), 1):
        lines += paragraph(f"{number}. {assumption}", size=9.5, bold=True)
        lines += paragraph(f"here: {remark}", size=9.5, indent=0.02, colour=COLOURS["muted"])
    return lines


def _cell(values: Mapping[str, float | int | None], digits: int = 1) -> str:
    return " ".join("-" if v is None else f"{v:.{digits}f}" if isinstance(v, float) else str(v)
                    for v in values.values())


TABLE_SIZE = 8.5


def _table(rows: list[list[str]]) -> list[Line]:
    """Monospace rows in columns as wide as their widest cell, the first row the header."""
    widths = [max(len(row[k]) for row in rows) + 2 for k in range(len(rows[0]))]
    return [Line("".join(f"{cell:<{w}}" for cell, w in zip(row, widths, strict=True)).rstrip(),
                 family="monospace", bold=k == 0, size=TABLE_SIZE)
            for k, row in enumerate(rows)]


def _segment_table(report: Report) -> list[Line]:
    """Every segment with its thresholds, max g and b per signal: a row each where the
    page is wide enough for the signals side by side, else a row per signal under each."""
    rows = [["segment", "mode", "start-end [s]", "thresholds", "max g", "b", "case"]] + [
        [s.name, s.mode, f"{s.start_s:.1f}-{s.end_s:.1f}", _cell(s.thresholds, 0),
         _cell(s.max_g), _cell(s.b), "-" if s.case is None else str(s.case)]
        for s in report.segments]
    signals = list(report.b)
    unjudged = [name for name in signals if name in report.not_judged]
    said = "Thresholds and g in percent of each signal's full scale." + (
        f" Not judged (their g raises no alarm): {', '.join(unjudged)}." if unjudged else "")
    side_by_side = _table(rows)
    if max(len(line.text) for line in side_by_side) <= columns(TABLE_SIZE, "monospace"):
        return paragraph(f"Columns per signal, in the order {', '.join(signals)}. {said}",
                         colour=COLOURS["muted"]) + side_by_side
    lines = paragraph(said, colour=COLOURS["muted"])
    for s, row in zip(report.segments, rows[1:], strict=True):
        lines.append(Line(f"{row[0]} ({row[1]}, {row[2]} s, case {row[6]})", size=TABLE_SIZE,
                          bold=True))
        lines += _table([["signal", "threshold", "max g", "b"]] + [
            [name, _cell({name: s.thresholds.get(name)}, 0), _cell({name: s.max_g.get(name)}),
             _cell({name: s.b.get(name)})] for name in signals])
    return lines


def detail_lines(report: Report) -> list[Line]:
    lines = _segment_table(report)
    active = report.active_diagnosis
    if active:
        lines += heading("Active diagnosis")
        for e in active.evidence:
            outcome = "a fault among" if e.faulty else "clears"
            lines += paragraph(f"{e.segment} at {e.start_s:.1f} s in {e.log}: b = "
                               f"{''.join(str(v) for v in e.b.values())} -> {outcome} "
                               f"{', '.join(e.tested)}")
        if active.recommended_dms:
            lines += paragraph("To decide, run " + " or ".join(active.recommended_dms)
                               + " on the next dive.")
    if report.notes:
        lines += heading("Notes")
        for note in report.notes:
            lines += paragraph(f"- {note}")
    return lines


def render_dive_report(report: Report, series: Series | None, target: Path) -> int:
    """Write the PDF; returns its page count."""
    name = Path(report.log).name
    title = f"auvdiag report: {name}"
    with pdf_document(target, title, f"Fault diagnosis of {report.log}") as pdf:
        # One flow of text: the segments follow the summary on its page where they fit,
        # rather than a page of their own that is mostly empty.
        text = [*first_page_lines(report, series), *heading("Segments and evidence"),
                *detail_lines(report)]
        # The page title names the log: a running title beside it would run into a long one.
        pages = write_text_pages(pdf, text, "", f"Diagnosis of {name}")
        if series is None or "measured" not in series:
            return pages
        for draw in (sensors_page, residual_page, change_page, effect_page, commands_page,
                     effort_page, substitution_page):
            figure = draw(report, series)
            if figure is not None:
                figure.suptitle(title, x=0.99, ha="right", fontsize=8, color=COLOURS["muted"])
                pdf.savefig(figure)
                pages += 1
    return pages
