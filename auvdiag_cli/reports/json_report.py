"""The machine-readable report (SPEC §5) at the edge: the typed `Report` as the plain dict
json.dumps writes, and the verdict in words for a saved report's title."""

from auvdiag_cli.engine.coverage import normal_verdict_text
from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.report_build import build_report, utc_text

__all__ = ["diagnosis_to_dict", "utc_text", "verdict_title"]

NOTHING_JUDGED = "no signal could be judged"


def diagnosis_to_dict(diagnosis: Diagnosis) -> dict[str, object]:
    return build_report(diagnosis).to_json()


def verdict_title(report: Report) -> str:
    """The verdict in words: the component a fault names, and how much a NORMAL covered
    when it did not cover everything."""
    if report.verdict == "normal":
        coverage = report.coverage
        return normal_verdict_text(None if coverage is None else coverage.summary,
                                   True if coverage is None else coverage.complete)
    if report.verdict == "fault":
        named = report.named.replace("_", " ")
        return f"FAULT: {named or 'component not identified'}"
    if report.verdict == "undetermined":
        return f"UNDETERMINED: {report.undetermined_because or NOTHING_JUDGED}"
    return report.verdict.upper()
