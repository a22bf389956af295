"""One error contract: every error a user can act on is an `AuvdiagError`, shown as one line
with exit status 2 by every command and recorded as a final result by audit workers; damaged
logs are analysed and say so (`completeness`), clocks and summaries that the files got wrong
cost a record, not the log."""

import json
import re
import shutil
import struct
from importlib import resources

import numpy as np
import pandas as pd
import pypdf
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
FORMATS = ["bag", "db3", "ros2-mcap", "mcap", "tlog", "bin"]


def run(*args):
    result = runner.invoke(app, list(map(str, args)))
    assert "Traceback" not in result.output and "unexpected" not in result.output
    return result


def test_every_layer_raises_the_one_root():
    from auvdiag_errors import AuvdiagError, LogError, ModelError, ProfileError, UsageError
    from models.store import ModelFileError

    for error in (LogError, ModelFileError, ModelError, ProfileError, UsageError):
        assert issubclass(error, AuvdiagError)
    assert "\n" not in str(LogError("x.bag", "Could not parse:\n  line one\n  line two"))


def test_audit_worker_records_a_model_it_cannot_load_as_final(make_log, tmp_path):
    from auvdiag_cli.audit.worker import AuditTask, analyse

    outcome = analyse(AuditTask(str(make_log("paper-normal", 11, "tlog")), None,
                                str(tmp_path)))
    assert outcome.final and outcome.document is None
    assert "not a model directory" in outcome.error and "unexpected" not in outcome.error


@pytest.fixture(scope="module")
def elsewhere_profile(tmp_path_factory):
    """The built-in profile with every topic and message renamed to one no log has."""
    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    text = re.sub(r'(topic|message) = "([^"]+)"', r'\1 = "ELSEWHERE_\2"', text)
    path = tmp_path_factory.mktemp("profile") / "elsewhere.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("fmt", FORMATS)
def test_inspect_lists_a_log_holding_none_of_the_signals(make_log, elsewhere_profile, fmt):
    result = run("inspect", make_log("paper-normal", 11, fmt), "--profile", elsewhere_profile)
    assert result.exit_code == 2
    listed = {"tlog": "ATTITUDE", "bin": "RCOU"}.get(fmt, "/imu/data")
    assert listed in result.stdout
    assert result.stdout.count("MISSING") == 4


def test_inspect_without_a_mapping_for_the_format_lists_the_log(make_log):
    result = run("inspect", make_log("paper-normal", 11, "bag"), "--profile", "arducopter_quad")
    assert result.exit_code == 2
    assert "/imu/data" in result.stdout and "no [sources.ros] mapping" in result.stdout


def _dataflash_times(data: bytes, name: bytes) -> list[int]:
    """Offsets of the TimeUS field of every record of message ``name``."""
    type_id = data[data.index(name) - 2]
    header = bytes([0xA3, 0x95, type_id])
    return [m.start() + 3 for m in re.finditer(re.escape(header), data)]


@pytest.mark.parametrize(("where", "value"), [
    (where, value) for where in ("first", "middle", "last")
    for value in (2**40, 2**62, 2**64 - 1, 0) if (where, value) != ("first", 0)])
def test_one_corrupted_dataflash_timestamp_costs_one_record(make_log, tmp_path, where, value):
    source = make_log("paper-flow-sensor-covered", 31, "bin")
    data = bytearray(source.read_bytes())
    fields = _dataflash_times(bytes(data), b"RCOU")
    offset = {"first": fields[0], "middle": fields[len(fields) // 2], "last": fields[-1]}[where]
    struct.pack_into("<Q", data, offset, value)
    damaged = tmp_path / "clock.bin"
    damaged.write_bytes(bytes(data))
    shown = run("inspect", damaged)
    span = re.search(r"span\s+([\d.]+) … ([\d.]+) s on the log.s clock", shown.stdout)
    assert span and float(span.group(1)) < 0.1 and 174.9 < float(span.group(2)) < 175.1
    result = run("diagnose", damaged, "--json", "-", "--quiet")
    report = json.loads(result.stdout)
    assert result.exit_code == 1 and report["component"] == "flow_sensor"
    assert 174.5 < report["duration_s"] < 175.0
    assert any("timestamp left out" in n or "impossible time" in n for n in report["notes"])


def test_a_clock_that_jumps_beyond_any_log_is_rejected_not_overflowed():
    from adapters.signals import Series, Signals
    from auvdiag_cli.engine.resample import resample

    times = np.arange(100, dtype=np.int64) * 100_000_000
    times[50:52] = [2**62, 2**62 + 100_000_000]        # two corrupt records in a row
    series = {name: Series(times, np.zeros(100), name) for name in ("c", "s")}
    signals = Signals(path=None, format="bin", start_ns=0, end_ns=int(times.max()),  # type: ignore[arg-type]
                      series=series)
    with pytest.raises(ValueError, match="damaged"):
        resample(signals, ("c",), ("s",), 0.1)


@pytest.fixture(scope="module")
def cut_log(make_log, tmp_path_factory):
    source = make_log("paper-flow-sensor-covered", 31, "tlog")
    target = tmp_path_factory.mktemp("cut") / "cut.tlog"
    target.write_bytes(source.read_bytes()[:200_000] + b"\xfd\x09")   # ends inside a frame
    return target


def test_a_salvaged_log_says_what_was_read(cut_log, tmp_path):
    result = run("diagnose", cut_log, "--json", tmp_path / "r.json", "--pdf",
                 tmp_path / "r.pdf")
    assert result.exit_code in (0, 1)
    assert "PARTIAL LOG" in result.stdout
    completeness = json.loads((tmp_path / "r.json").read_text())["completeness"]
    assert completeness["status"] == "partial"
    assert completeness["damage_at_byte"] == 200_000
    assert completeness["bytes_total"] == 200_002
    assert 40 < completeness["seconds_read"] < 175 and completeness["messages_read"] > 1000
    text = pypdf.PdfReader(tmp_path / "r.pdf").pages[0].extract_text()
    assert "PARTIAL LOG" in text and "damage at byte 200000" in text


def test_a_complete_log_says_so(make_log):
    report = json.loads(run("diagnose", make_log("paper-normal", 11, "mcap"), "--json", "-",
                            "--quiet").stdout)
    assert report["completeness"]["status"] == "complete"
    assert report["completeness"]["damage_at_byte"] is None


def test_audit_counts_salvage_and_fails_on_it_when_asked(cut_log, make_log, tmp_path):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    shutil.copy(cut_log, fleet / "cut.tlog")
    shutil.copy(make_log("paper-normal", 11, "tlog"), fleet / "whole.tlog")
    output = tmp_path / "out"
    plain = run("audit", fleet, "--output", output, "--jobs", "1", "--fail-on", "error")
    assert plain.exit_code == 0 and "1 partial (damaged)" in plain.output
    frame = pd.read_csv(output / "audit.csv").set_index("log")
    assert frame["completeness"].to_dict() == {str(fleet / "cut.tlog"): "partial",
                                               str(fleet / "whole.tlog"): "complete"}
    strict = run("audit", fleet, "--output", output, "--jobs", "1", "--fail-on", "damaged")
    assert strict.exit_code == 2


def test_report_from_an_incomplete_json_is_one_line(tmp_path):
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps({"log": "x.bag", "verdict": "normal"}))
    result = run("report", broken)
    assert result.exit_code == 2
    errors = [line for line in result.output.splitlines() if "error:" in line]
    assert len(errors) == 1 and "not a complete auvdiag report" in errors[0]


def test_report_with_damaged_time_histories_is_one_line(make_log, tmp_path):
    target = tmp_path / "r.json"
    run("diagnose", make_log("paper-normal", 11, "tlog"), "--json", target, "--quiet")
    (tmp_path / "r.series.npz").write_bytes(b"PK\x03\x04 not really a zip")
    result = run("report", target)
    assert result.exit_code == 2 and "unreadable time histories" in result.output


def _first_mcap_chunk(data: bytes) -> int:
    position = 8                                           # after the magic
    while data[position] != 0x06:                          # the Chunk opcode
        position += 9 + struct.unpack_from("<Q", data, position + 1)[0]
    return position


@pytest.mark.parametrize("value", [2**40, 2**63 + 5, 2**64 - 1])
def test_a_chunk_declaring_a_huge_size_is_damage_not_an_allocation(make_log, tmp_path, value):
    """The chunk's uncompressed size (after start and end times) is a length field."""
    data = bytearray(make_log("paper-normal", 11, "mcap").read_bytes())
    struct.pack_into("<Q", data, _first_mcap_chunk(bytes(data)) + 9 + 16, value)
    damaged = tmp_path / "huge.mcap"
    damaged.write_bytes(bytes(data))
    result = run("diagnose", damaged, "--quiet")
    assert result.exit_code == 2 and f"a chunk declares {value} bytes" in result.output


@pytest.mark.parametrize("value", [0, 2**31 - 1, 2**32 - 1])
def test_a_ros1_chunk_size_field_is_not_trusted(make_log, tmp_path, value):
    data = bytearray(make_log("paper-normal", 11, "bag").read_bytes())
    for match in re.finditer(rb"size=", bytes(data)):
        struct.pack_into("<I", data, match.end(), value)
    damaged = tmp_path / "sizes.bag"
    damaged.write_bytes(bytes(data))
    result = run("diagnose", damaged, "--quiet")
    assert result.exit_code in (0, 2)
