"""`--healthy FILE`: only the listed part of a log is trained on or calibrated with (a flight
that failed late still gives its healthy beginning); bad files are one line, exit 2."""

from pathlib import Path

import pytest
from typer.testing import CliRunner

from auvdiag_cli import api
from auvdiag_cli.cli import app
from auvdiag_cli.engine.ingest import ingest
from auvdiag_errors import LogError, UsageError

runner = CliRunner()
FAULTY = "paper-flow-sensor-covered"      # the flow sensor is covered at 115 s


def _healthy(tmp_path: Path, *rows: str) -> Path:
    path = tmp_path / "healthy.csv"
    path.write_text("\n".join(["log,start,end", *rows]) + "\n")
    return path


def _start_s(log: Path) -> float:
    return api.read_log(log, api.load_profile(None)).start_ns / 1e9


@pytest.mark.parametrize(("rows", "problem"), [
    (("run,10,5",), "line 2: the end is not after the start"),
    (("run,2024-05-01T10:00:00,",), "has no time zone"),
    (("run,soon,",), "neither seconds nor an ISO 8601 time"),
    (("run,,5", "run,,6"), "line 3: run is listed twice"),
])
def test_a_bad_healthy_file_names_the_file_and_line(tmp_path, rows, problem):
    path = _healthy(tmp_path, *rows)
    with pytest.raises(UsageError, match=problem) as raised:
        api.read_healthy_parts(path)
    assert str(path) in str(raised.value)


def test_a_healthy_file_without_its_header_is_refused_on_the_command_line(tmp_path, make_log):
    path = tmp_path / "healthy.csv"
    path.write_text("run,1,2\n")
    result = runner.invoke(app, ["train", str(make_log("mission-ccw", 12)), "--output",
                                 str(tmp_path / "m"), "--healthy", str(path)])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and "log,start,end" in lines[0]
    assert not (tmp_path / "m").exists()


def test_a_part_on_the_logs_clock_crops_it_in_seconds_or_iso(make_log, tmp_path):
    from datetime import UTC, datetime

    log = make_log(FAULTY, 31)
    start = _start_s(log)
    iso = datetime.fromtimestamp(start + 100.0, UTC).isoformat()
    parts = api.read_healthy_parts(_healthy(tmp_path, f"{log.name},{start + 20.0:.3f},{iso}"))
    frame = ingest(log, api.load_profile(None), part=parts.of(log)).frame
    assert frame.time_s[0] == pytest.approx(0.0, abs=0.2)
    assert frame.time_s[-1] == pytest.approx(80.0, abs=0.2)
    assert parts.of(log.parent / "other") == (None, None)


def test_a_part_outside_the_log_is_one_error_with_its_span(make_log, tmp_path):
    log = make_log(FAULTY, 31)
    parts = api.read_healthy_parts(_healthy(tmp_path, f"{log.name},1,2"))
    with pytest.raises(LogError, match=r"holds no sample of .* the log spans"):
        ingest(log, api.load_profile(None), part=parts.of(log))


def test_calibrating_with_the_healthy_part_leaves_the_fault_out(make_log, tmp_path):
    log = make_log(FAULTY, 31)
    profile = api.load_profile(None)
    end = f"{_start_s(log) + 105.0:.3f}"
    healthy = api.read_healthy_parts(_healthy(tmp_path, f"{log},,{end}"))

    def flow_threshold(options: api.CalibrateOptions) -> float:
        model = api.load_model(None)
        api.calibrate([log], profile, model, options=options)
        return model.card.thresholds["mission"]["flow"]

    whole, healthy_only = (flow_threshold(api.CalibrateOptions()),
                           flow_threshold(api.CalibrateOptions(healthy=healthy)))
    assert whole > 100.0            # the covered sensor's g (about 98 %) times the margin
    assert healthy_only < whole / 3


# Which parts are trained on does not depend on the predictors: two of the four.
CHEAP = ("network", "linear")


def test_training_on_the_healthy_part_says_so_and_uses_only_it(make_log, tmp_path):
    log, other = make_log(FAULTY, 31), make_log("mission-ccw", 12)
    end = f"{_start_s(log) + 90.0:.3f}"
    said: list[str] = []
    options = api.TrainOptions(hidden=8, iterations_scale=0.02, keep_unskilled=True,
                               predictors=CHEAP, healthy=api.read_healthy_parts(_healthy(
                                   tmp_path, f"{log.name},,{end}", "gone.bag,,5")))
    result = api.train([log, other], api.load_profile(None), tmp_path / "m", options=options,
                       progress=said.append)
    whole = api.train([log, other], api.load_profile(None), tmp_path / "w",
                      options=api.TrainOptions(hidden=8, iterations_scale=0.02,
                                               keep_unskilled=True, predictors=CHEAP))
    assert any(f"{log.name}: only its healthy part" in line for line in said)
    assert any("1 listed log(s) not among those given: gone.bag" in line for line in said)
    skipped_s = (whole.operating_hours - result.operating_hours) * 3600
    duration_s = api.read_log(log, api.load_profile(None)).end_ns / 1e9 - _start_s(log)
    assert skipped_s == pytest.approx(duration_s - 90.0, abs=2.0)
