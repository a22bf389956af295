"""The bundled sample logs still give the reports recorded beside them, and their truth."""

import json
from pathlib import Path

import pytest
from helpers import diagnose_json

SAMPLES = Path(__file__).parents[1] / "sample_logs"
EXPECTED = sorted(SAMPLES.glob("*.expected.json"))


def test_there_is_a_normal_and_a_faulty_sample_in_every_format():
    reports = [json.loads(p.read_text()) for p in EXPECTED]
    kinds = {(r["format"], r["verdict"]) for r in reports}
    for fmt in ("bag", "db3", "ros2-mcap", "mcap", "tlog", "bin"):
        assert {(fmt, "normal"), (fmt, "fault")} <= kinds, fmt
    assert {"flow_sensor", "yaw_rate_sensor"} <= {r["component"] for r in reports}


@pytest.mark.parametrize("expected_path", EXPECTED, ids=lambda p: p.name.split(".")[0])
def test_sample_log_report_matches_expected_and_truth(expected_path):
    expected = json.loads(expected_path.read_text())
    truth = json.loads(expected_path.with_name(
        expected_path.name.replace(".expected.json", ".truth.json")).read_text())
    log = SAMPLES.parent / expected["log"]
    exit_code, report = diagnose_json(log)
    assert exit_code == (1 if expected["verdict"] == "fault" else 0)
    assert set(report) == set(expected)                 # the schema did not drift
    for key in ("verdict", "component", "candidates", "case", "b", "format", "duration_s",
                "segment_source", "not_judged", "coverage", "completeness"):
        assert report[key] == expected[key], key
    assert [(s["name"], s["mode"], s["b"]) for s in report["segments"]] == [
        (s["name"], s["mode"], s["b"]) for s in expected["segments"]]
    assert report["commands_check"]["named"] == expected["commands_check"]["named"]
    for key in ("judged", "off"):
        assert report["start_check"][key] == expected["start_check"][key], key
    for key in ("onset_s", "detected_at_s"):
        assert (report[key] is None) == (expected[key] is None)
        if expected[key] is not None:
            assert report[key] == pytest.approx(expected[key], abs=0.5)
    assert report["verdict"] == truth["expected"]["verdict"]
    if truth["fault"] is not None:
        assert truth["fault"]["component"] in report["candidates"]
        assert abs(report["onset_s"] - truth["fault"]["onset_s"]) < 2.0
