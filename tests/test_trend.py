"""Fleet health over time: the trend test, and a simulated season in which one vehicle's
thruster loses thrust every week: flagged weeks before its first alarm; the healthy vehicles
never."""

import json
from dataclasses import replace

import pytest
from pypdf import PdfReader
from typer.testing import CliRunner

from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.audit.trend import flag_history, fleet_trend, mann_kendall, sen_slope
from auvdiag_cli.cli import app
from auvdiag_cli.simulator.season import write_season

pytestmark = pytest.mark.slow    # trains models or simulates fleets

runner = CliRunner()
WEEKS, LOSS_PER_WEEK = 10, 0.04


def test_mann_kendall_and_sen_slope_on_known_series():
    s, p = mann_kendall([1, 2, 3, 4, 5, 6, 7, 8])
    assert s == 28 and p < 0.001
    assert mann_kendall([5, 5, 5, 5, 5, 5]) == (0, 1.0)
    s, p = mann_kendall([8, 7, 6, 5, 4, 3])
    assert s == -15 and p == 1.0
    # 8 pairs rise, 2 fall: S = 6; var = 5·4·15/18 = 16.67, z = 5/4.08, p = 0.110
    assert mann_kendall([1, 3, 2, 5, 4]) == (6, pytest.approx(0.1103, abs=1e-3))
    assert sen_slope([0.0, 0.1, 0.2, 0.3, 5.0]) == pytest.approx(0.1)


def _record(log, date, flow, verdict="normal"):
    return AuditRecord.from_report({
        "log": log, "start_time_utc": date, "verdict": verdict, "not_judged": {},
        "segments": [{"name": "MISSION", "start_s": 0.0, "end_s": 60.0, "mode": "mission",
                      "max_g": {"flow": flow, "yaw_rate": 2.0},
                      "thresholds": {"flow": 10.0, "yaw_rate": 10.0}}]})


def test_a_rising_margin_is_flagged_and_an_alarm_is_not_a_trend():
    rising = [_record(f"fleet/a/d{k}.tlog", f"2026-01-{k + 1:02d}T00:00:00", 1.0 + k)
              for k in range(8)]
    flat = [_record(f"fleet/b/d{k}.tlog", f"2026-01-{k + 1:02d}T00:00:00", 3.0 + (k % 2))
            for k in range(8)]
    trend = fleet_trend(rising + flat)
    assert trend.flagged_vehicles == ["a"]
    assert trend.flagged[0].signal == "flow"
    alarmed = [*rising, _record("fleet/a/d9.tlog", "2026-01-10T00:00:00", 12.0, "fault")]
    assert fleet_trend(alarmed).flagged == []
    # Dates, not file names, order the dives.
    shuffled = [replace(r, log=f"fleet/a/z{9 - k}.tlog") for k, r in enumerate(rising)]
    assert fleet_trend(shuffled).flagged_vehicles == ["a"]


@pytest.fixture(scope="module")
def season(tmp_path_factory, profile):
    root = tmp_path_factory.mktemp("season")
    write_season(root / "fleet", profile, ["auv-1", "auv-2", "auv-3"], "auv-2", WEEKS,
                 LOSS_PER_WEEK)
    result = runner.invoke(app, ["audit", str(root / "fleet"), "--output", str(root / "out"),
                                 "--jobs", "2"])
    assert result.exit_code == 1, result.output     # the worn thruster alarms at last
    assert "0 not analysable" in result.output
    return root / "out"


def test_the_worn_vehicle_is_flagged_weeks_before_its_first_alarm(season):
    records = [AuditRecord.from_report(json.loads(p.read_text()))
               for p in (season / "logs").glob("*.json")]
    history = flag_history(records)
    assert set(history) == {"auv-1", "auv-2", "auv-3"}
    for healthy in ("auv-1", "auv-3"):
        assert not any(d.flagged or d.alarmed for d in history[healthy])
    worn = history["auv-2"]
    first_alarm = next(k for k, d in enumerate(worn) if d.alarmed)
    first_flag = next(k for k, d in enumerate(worn) if d.flagged)
    assert first_flag <= first_alarm - 2, [(d.flagged, d.alarmed) for d in worn]


def test_trend_command_and_the_fleet_pdf(season, tmp_path):
    # At the season's end the worn vehicle alarms: that is no longer a trend to warn of.
    result = runner.invoke(app, ["trend", str(season)])
    assert result.exit_code == 0, result.output
    assert "auv-2 yaw_rate" in result.output and "already alarming" in result.output
    # Seven weeks in, before any alarm, the trend command warns of it alone.
    early = tmp_path / "logs"
    early.mkdir()
    for report in (season / "logs").glob("*.json"):
        if int(report.name.split("week-")[1][:2]) < 7:
            (early / report.name).write_text(report.read_text())
    result = runner.invoke(app, ["trend", str(tmp_path)])
    assert result.exit_code == 1, result.output
    shrinking = result.output.split("every vehicle and signal:")[0]
    assert "auv-2" in shrinking and "MARGIN SHRINKING" in shrinking
    assert "auv-1" not in shrinking and "auv-3" not in shrinking
    text = "".join(page.extract_text() for page in PdfReader(season / "audit.pdf").pages)
    assert "Health over time" in text and "auv-2: 10 dives, oldest first" in text
    missing = runner.invoke(app, ["trend", str(season / "logs")])
    assert missing.exit_code == 2 and "not an audit folder" in missing.stderr
