"""`auvdiag audit` on a real folder: every format, a damaged log, an unrelated file; killed
halfway and resumed; changed inputs redone; and the same audit on a Dask LocalCluster."""

import json
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pypdf
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from models.store import default_model_dir

pytestmark = pytest.mark.slow    # trains models or simulates fleets

runner = CliRunner()
# (scenario, format, expected verdict, expected component or candidates)
FLEET = [
    ("paper-flow-sensor-covered", "bag", "fault", "flow_sensor"),
    ("paper-normal", "db3", "normal", None),
    ("mission-yaw-rate-sensor-dead", "ros2-mcap", "fault", "yaw_rate_sensor"),
    ("mission-thruster-0-dead", "mcap", "fault", "thruster_0"),
    ("mission-fast-ccw", "tlog", "normal", None),
    ("mission-large-cw", "bin", "normal", None),
]
SUFFIXES = {"bag": ".bag", "mcap": ".mcap", "tlog": ".tlog", "bin": ".bin"}
STABLE_COLUMNS = ["log", "format", "verdict", "component", "candidates", "case", "onset_s",
                  "detected_at_s", "worst_g_ratio", "error"]


def _copy(source: Path, target: Path) -> Path:
    if source.is_dir():
        shutil.copytree(source, target)
    else:
        shutil.copy(source, target)
    return target


@pytest.fixture(scope="module")
def fleet(make_log, tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("fleet")
    for scenario, fmt, _, _ in FLEET:
        _copy(make_log(scenario, 11, fmt), folder / f"{scenario}{SUFFIXES.get(fmt, '')}")
    whole = (folder / "paper-flow-sensor-covered.bag").read_bytes()
    (folder / "damaged.bag").write_bytes(whole[:20_000])     # cut inside the first chunk
    (folder / "notes.txt").write_text("dive notes, not a log\n")
    (folder / "paper-normal.truth.json").write_text("{}")      # a companion file
    return folder


def audit(*args: str) -> tuple[int, str]:
    result = runner.invoke(app, ["audit", *args])
    return result.exit_code, result.output


def table(output: Path) -> pd.DataFrame:
    return pd.read_csv(output / "audit.csv")


@pytest.fixture(scope="module")
def full_audit(fleet, tmp_path_factory) -> Path:
    output = tmp_path_factory.mktemp("audit")
    code, text = audit(str(fleet), "--output", str(output), "--jobs", "2")
    assert code == 2, text          # a log could not be analysed
    return output


def test_every_format_gets_its_row(full_audit, fleet):
    rows = table(full_audit).set_index("log")
    assert len(rows) == len(FLEET) + 1
    for scenario, fmt, verdict, component in FLEET:
        name = f"{scenario}{'' if fmt in ('db3', 'ros2-mcap') else '.' + fmt}"
        row = rows.loc[str(fleet / name)]
        assert row["format"] == fmt
        assert row["verdict"] == verdict
        named = row["component"] if isinstance(row["component"], str) else row["candidates"]
        assert (named if isinstance(named, str) else None) == component
        assert pd.isna(row["error"])
    damaged = rows.loc[str(fleet / "damaged.bag")]
    assert damaged["verdict"] == "error"
    assert "damaged.bag" in damaged["error"]


def test_parquet_matches_csv_and_json_per_log(full_audit):
    csv, parquet = table(full_audit), pd.read_parquet(full_audit / "audit.parquet")
    assert list(parquet["log"]) == list(csv["log"])
    assert list(parquet["verdict"]) == list(csv["verdict"])
    for result_file in csv["result_file"]:
        report = json.loads((full_audit / "logs" / result_file).read_text())
        assert report["audit"]["result_file"] == result_file


def test_fleet_pdf_lists_problems_and_skipped_files(full_audit):
    reader = pypdf.PdfReader(full_audit / "audit.pdf")
    assert len(reader.pages) >= 2
    summary = reader.pages[0].extract_text()
    assert "7 logs: 3 normal, 3 with a fault, 0 undetermined, 1 not analysable" in summary
    assert "damaged.bag" in summary
    assert "notes.txt" in summary                       # the unrelated file, listed
    assert "paper-normal.truth.json" not in summary     # a log's companion, only counted
    assert "1 files named after a log" in summary
    assert "Verdicts by vehicle and date" in reader.pages[-2].extract_text()
    assert "Health over time" in reader.pages[-1].extract_text()


def test_fail_on_chooses_what_counts(full_audit, fleet):
    assert audit(str(fleet), "--output", str(full_audit), "--fail-on", "fault")[0] == 1
    assert audit(str(fleet), "--output", str(full_audit), "--fail-on", "none")[0] == 0


def test_killed_audit_resumes_without_redoing_finished_logs(fleet, full_audit, tmp_path):
    output = tmp_path / "audit"
    process = subprocess.Popen(
        [sys.executable, "-m", "auvdiag_cli", "audit", str(fleet), "--output", str(output),
         "--jobs", "1"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    results = output / "logs"
    deadline = time.monotonic() + 120
    while len(list(results.glob("*.json"))) < 3 and process.poll() is None:
        assert time.monotonic() < deadline, "the audit never got going"
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    process.wait()
    finished = {p.name: p.stat().st_mtime_ns for p in results.glob("*.json")}
    assert 3 <= len(finished) < len(FLEET) + 1, "killed too late to test resuming"

    code, text = audit(str(fleet), "--output", str(output), "--jobs", "2")
    assert code == 2
    assert f"{len(finished)} reused" in text
    for name, mtime in finished.items():
        assert (results / name).stat().st_mtime_ns == mtime, f"{name} was recomputed"
    resumed, reference = table(output), table(full_audit)
    pd.testing.assert_frame_equal(resumed[STABLE_COLUMNS], reference[STABLE_COLUMNS])


def test_changed_log_or_model_is_redone(make_log, tmp_path):
    folder, output = tmp_path / "logs", tmp_path / "audit"
    folder.mkdir()
    model = _copy(default_model_dir(), tmp_path / "model")
    log = _copy(make_log("paper-normal", 11, "bag"), folder / "dive.bag")
    assert "1 diagnosed now, 0 reused" in audit(str(folder), "-o", str(output), "--model",
                                                 str(model))[1]
    assert "0 diagnosed now, 1 reused" in audit(str(folder), "-o", str(output), "--model",
                                                 str(model))[1]
    shutil.copy(make_log("mission-thruster-0-dead", 11, "bag"), log)
    code, text = audit(str(folder), "-o", str(output), "--model", str(model))
    assert code == 1 and "1 diagnosed now, 0 reused" in text
    metadata = json.loads((model / "model.json").read_text())
    metadata["thresholds"]["mission"]["flow"] = 20.0
    (model / "model.json").write_text(json.dumps(metadata))
    assert "1 diagnosed now, 0 reused" in audit(str(folder), "-o", str(output), "--model",
                                                 str(model))[1]


def test_bad_model_stops_the_audit_before_it_starts(fleet, tmp_path):
    code, text = audit(str(fleet), "-o", str(tmp_path / "out"), "--model", str(tmp_path))
    assert code == 2 and "not a model directory" in text
    assert not (tmp_path / "out" / "audit.csv").exists()


def test_audit_on_a_dask_local_cluster(fleet, full_audit, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        output = tmp_path / "dask"
        code, text = audit(str(fleet), "--output", str(output), "--scheduler",
                           cluster.scheduler_address)
    assert code == 2, text
    pd.testing.assert_frame_equal(table(output)[STABLE_COLUMNS],
                                  table(full_audit)[STABLE_COLUMNS])


def test_a_dask_audit_does_not_leave_fetched_results_on_the_workers(fleet):
    """Each log's time histories stay in a worker's memory while the audit holds its future;
    held to the end, a fleet's worth piles up on the workers."""
    distributed = pytest.importorskip("distributed")
    from auvdiag_cli.audit.runner import run_dask
    from auvdiag_cli.audit.worker import AuditTask

    tasks = [AuditTask(str(fleet / f"{scenario}{SUFFIXES.get(fmt, '')}"), None, None)
             for scenario, fmt, _, _ in FLEET]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        outcomes = run_dask(tasks, cluster.scheduler_address)
        fetched = [next(outcomes) for _ in tasks]      # the audit still running, at its last

        def held() -> int:
            return sum(client.run(lambda dask_worker: len(dask_worker.data)).values())

        deadline = time.monotonic() + 10
        while held() > 1 and time.monotonic() < deadline:
            time.sleep(0.2)
        assert held() <= 1          # at most the last result, released when the audit goes on
        outcomes.close()
    assert all(outcome.document is not None for outcome in fetched)


def test_unreachable_scheduler_is_one_line(fleet, tmp_path):
    code, text = audit(str(fleet), "-o", str(tmp_path / "out"), "--scheduler",
                       "tcp://127.0.0.1:9")
    assert code == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in text


@pytest.mark.skipif(not Path("/proc/self/status").is_file(), reason="needs Linux's VmHWM")
def test_a_worker_started_by_a_large_program_reports_its_own_memory():
    """The peak memory an audit records for a log is its worker's own, not that of the
    program that started it (ru_maxrss carries the parent's peak across the exec)."""
    import resource

    held = bytearray(400 << 20)
    held[::4096] = b"\1" * len(held[::4096])            # resident, not merely reserved
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 > 400
    reported = subprocess.run(
        [sys.executable, "-c", "from auvdiag_cli.peak_memory import peak_rss_mb; "
         "print(peak_rss_mb())"], capture_output=True, text=True, check=True).stdout
    del held
    assert 1 < float(reported) < 100


@pytest.mark.parametrize(("starts", "widest_h"), [
    (["2026-11-22T10:00:00+00:00"] * 5, 2.0),               # one time (simulated dives)
    ([f"2026-11-22T10:0{i}:00+00:00" for i in range(5)], 2.0),   # minutes apart
    ([f"2026-11-2{i}T10:00:00+00:00" for i in range(5)], 6 * 24.0)])
def test_the_fleet_timeline_spans_the_logs_not_years(starts, widest_h):
    """Logs of one day (or of one moment) are drawn across hours, not across the years of
    matplotlib's margin for a date axis with no span."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.dates as mdates
    import matplotlib.pyplot as plt

    from auvdiag_cli.audit.fleet_pdf import _timeline
    from auvdiag_cli.audit.record import AuditRecord

    rows = [AuditRecord(log=f"dive{i}.mcap", verdict="normal", fleet_vehicle="rov",
                        start_time_utc=start) for i, start in enumerate(starts)]
    figure, ax = plt.subplots()
    _timeline(ax, rows)
    low, high = (mdates.num2date(x) for x in ax.get_xlim())
    plt.close(figure)
    first, last = (mdates.num2date(mdates.datestr2num(s)) for s in (starts[0], starts[-1]))
    assert low <= first <= last <= high
    assert (high - low).total_seconds() / 3600 <= widest_h


def test_a_short_fleet_summary_shares_its_page_with_the_charts(tmp_path):
    """A few lines of summary are not a page of their own: the charts are drawn below."""
    import pypdfium2

    from auvdiag_cli.audit.fleet_pdf import render_fleet_report
    from auvdiag_cli.audit.record import AuditRecord

    rows = [AuditRecord(log=f"dive{i}.mcap", verdict="fault" if i == 2 else "normal",
                        component="thruster_0" if i == 2 else None, fleet_vehicle="rov",
                        start_time_utc=f"2026-11-22T1{i}:00:00+00:00", worst_g_ratio=0.5 + i)
            for i in range(4)]
    target = tmp_path / "fleet.pdf"
    render_fleet_report(rows, [], target)
    page = pypdfium2.PdfDocument(target)[0].render(scale=0.5).to_pil().convert("L")
    pixels = np.asarray(page)
    lower = pixels[pixels.shape[0] // 2:]
    assert (lower < 128).mean() > 0.01, "the first page's lower half is empty"


def test_a_stored_result_this_release_cannot_read_is_done_again(tmp_path):
    """A stored report whose shape does not read (damaged, or from another release) with
    the right digests is diagnosed again, never a crash of the audit."""
    from auvdiag_cli import api

    fleet = tmp_path / "fleet"
    fleet.mkdir()
    samples = Path(__file__).resolve().parents[1] / "sample_logs"
    shutil.copy(samples / "mission-fast-ccw.tlog", fleet)
    first = api.audit([fleet], None, None, tmp_path / "out")
    assert first.computed == 1
    stored = next((tmp_path / "out" / "logs").glob("*.json"))
    document = json.loads(stored.read_text())
    stored.write_text(json.dumps({**document, "segments": {"not": "a list"}}))
    again = api.audit([fleet], None, None, tmp_path / "out")
    assert again.reused == 0 and again.computed == 1 and again.records[0].verdict == "normal"


def test_the_fleet_headline_is_wrapped_within_the_page():
    """A fleet of every kind of verdict: the headline says them all, each line of it within
    the page (it had run off the page's edge)."""
    from auvdiag_cli.audit.fleet_pdf import summary_lines
    from auvdiag_cli.audit.record import AuditRecord
    from auvdiag_cli.engine.coverage import Coverage
    from auvdiag_cli.reports.pdf.text import columns

    part = Coverage(("roll",), ("roll",), (), (), False, judged_from_s=31.0)
    rows = [*(AuditRecord(log=f"n{k}", verdict="normal") for k in range(120)),
            *(AuditRecord(log=f"p{k}", verdict="normal", coverage=part) for k in range(140)),
            *(AuditRecord(log=f"f{k}", verdict="fault") for k in range(250)),
            *(AuditRecord(log=f"u{k}", verdict="undetermined") for k in range(10)),
            *(AuditRecord(log=f"e{k}", error="not a log") for k in range(3))]
    headline = [line for line in summary_lines(rows, [], 0, False) if line.size == 14]
    assert len(headline) > 1 and all(len(line.text) <= columns(14, bold=True)
                                     for line in headline)
    assert " ".join(line.text.strip() for line in headline) == (
        "523 logs: 120 normal and 140 normal judged in part, 250 with a fault, "
        "10 undetermined, 3 not analysable")


def test_fleet_charts_show_only_what_the_logs_hold():
    """The verdict legend lists the verdicts the logs got (beside the bars, not over them);
    a fleet whose every signal is left to the change test says there is no g to rank."""
    from auvdiag_cli.audit.fleet_pdf import charts_page
    from auvdiag_cli.audit.record import AuditRecord

    rows = [AuditRecord(log="a", verdict="fault", component="engine"),
            AuditRecord(log="b", verdict="normal")]
    page = charts_page(rows)
    verdicts, _, _, worst = page.axes
    assert [t.get_text() for t in verdicts.get_legend().get_texts()] == ["normal", "fault"]
    assert [t.get_text() for t in worst.texts] == ["no log has a signal the replay judges"]
