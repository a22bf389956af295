"""The typed report: every sample's JSON report read into it and written back is the same
JSON, byte for byte; a report of an older release (keys missing) still reads; a document
that is not a report is refused."""

import json
from pathlib import Path

import pytest

from auvdiag_cli.reports.report import HypothesisPart, Report, SegmentPart

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"
EXPECTED = sorted(SAMPLES.glob("*.expected.json"))


@pytest.mark.parametrize("path", EXPECTED, ids=lambda p: p.name.split(".")[0])
def test_every_sample_report_round_trips_byte_for_byte(path):
    text = path.read_text()
    report = Report.from_json(json.loads(text))
    assert json.dumps(report.to_json(), indent=2) + "\n" == text
    assert all(isinstance(s, SegmentPart) for s in report.segments)
    if report.hypotheses is not None:
        assert isinstance(report.hypotheses.best, HypothesisPart)


def test_the_samples_cover_the_report_s_parts():
    reports = [Report.read(p) for p in EXPECTED]
    assert any(r.substitution and r.substitution.closed_loop for r in reports)
    assert any(r.active_diagnosis for r in reports) and any(r.hypotheses for r in reports)
    assert any(r.start_check for r in reports) and any(r.commands_check for r in reports)


def test_an_older_report_reads_with_its_missing_keys_empty():
    report = Report.from_json({"log": "dive.bag", "verdict": "fault", "component": "flow_sensor",
                               "hypotheses": {"best": {"component": "flow_sensor",
                                                       "kind": "dead"}}})
    assert report.named == "flow_sensor" and report.segments == () and report.coverage is None
    assert report.hypotheses is not None and report.hypotheses.best.description is None


@pytest.mark.parametrize("document", [{"verdict": "fault"}, {"log": "x", "verdict": "fault",
                                                              "segments": {"a": 1}}, []])
def test_a_document_that_is_no_report_is_refused(document):
    with pytest.raises(ValueError):
        Report.from_json(document)
