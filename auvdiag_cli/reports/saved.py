"""A diagnosis as files: the JSON report with its time histories beside it, the PDF and the
MCAP; and the PDF drawn again from a saved JSON report, without the log or the model."""

import json
from pathlib import Path

from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.files import write_json
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.report_build import build_report
from auvdiag_cli.reports.series import (
    Series,
    load_series,
    save_series,
    series_from_diagnosis,
    series_path,
)
from auvdiag_errors import UsageError

# What every report this tool writes holds, and its PDF is drawn from.
DRAWN_FROM = ("format", "vehicle", "b", "segments", "coverage", "model", "method")


def write_diagnosis_files(diagnosis: Diagnosis, json_path: Path | None = None,
                          pdf: Path | None = None, mcap: Path | None = None) -> None:
    """As many of the JSON report (with NAME.series.npz beside it), the PDF and the MCAP
    as are asked for."""
    report, series = build_report(diagnosis), series_from_diagnosis(diagnosis)
    if json_path is not None:
        sidecar = series_path(json_path)
        save_series(series, sidecar)
        write_json({**report.to_json(), "series_file": sidecar.name}, json_path)
    if pdf is not None:
        render_pdf(report, series, pdf)
    if mcap is not None:
        from auvdiag_cli.reports.mcap_export import write_diagnosis_mcap

        write_diagnosis_mcap(report, series, mcap)


def render_pdf(report: Report, series: Series | None, target: Path) -> None:
    """The dive's PDF report; a place that cannot be written is the user's error."""
    from auvdiag_cli.reports.pdf.dive import render_dive_report

    try:
        render_dive_report(report, series, target)
    except OSError as error:
        raise UsageError(f"{target}: cannot write the PDF: {error.strerror or error}") from None


def redraw_report(json_report: Path, target: Path) -> bool:
    """Draw the PDF of the saved JSON report at ``json_report`` into ``target``; False when
    its time histories are not beside it (the PDF then has its summary pages only)."""
    document = _read_report(json_report)
    named = document.get("series_file")
    sidecar = json_report.with_name(named) if isinstance(named, str) and named else None
    series = load_series(sidecar) if sidecar is not None and sidecar.is_file() else None
    try:
        render_pdf(Report.from_json(document), series, target)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as error:
        # The document came from a file: a field missing or of the wrong kind is the file's
        # problem, not a bug (reports this version writes are drawn in tests).
        raise UsageError(f"{json_report}: not a complete auvdiag report "
                         f"({type(error).__name__}: {error})") from None
    return series is not None


def _read_report(path: Path) -> dict[str, object]:
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise UsageError(f"{path}: not a readable JSON report: {error}") from None
    if not isinstance(document, dict) or "verdict" not in document or "log" not in document:
        raise UsageError(f"{path}: not an auvdiag JSON report (no 'verdict' or 'log')")
    missing = [key for key in DRAWN_FROM if key not in document]
    if missing:
        raise UsageError(f"{path}: not a complete auvdiag report (no {', '.join(missing)})")
    return document
