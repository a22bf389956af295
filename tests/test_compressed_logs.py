"""Text logs kept gzip-compressed (`.alog.gz` as pLogger's CompressAlogs writes it, a
`.csv.gz`): recognised by content, read as the plain log reads, a damaged stream read up to
its damage."""

import csv
import gzip
import shutil
from pathlib import Path

import numpy as np
import pytest
from test_moos_alog import LOGSTART_NS, _profile, _write_alog
from typer.testing import CliRunner

from adapters import detect_format, inventory, read_log
from adapters.identity import log_identity
from auvdiag_cli.cli import app
from auvdiag_cli.vehicle.profile import load_profile
from auvdiag_errors import LogError


def _gzip(path: Path, target: Path) -> Path:
    target.write_bytes(gzip.compress(path.read_bytes(), mtime=0))
    return target


def _same(a, b) -> None:
    assert (a.format, a.start_ns, a.end_ns, a.notes) == (b.format, b.start_ns, b.end_ns, b.notes)
    assert set(a.series) == set(b.series)
    for name in a.series:
        assert np.array_equal(a.series[name].times_ns, b.series[name].times_ns)
        assert np.array_equal(a.series[name].values, b.series[name].values, equal_nan=True)


def test_a_compressed_alog_reads_as_the_plain_one(tmp_path):
    plain = _write_alog(tmp_path / "LOG_KAYAK.alog")
    packed = _gzip(plain, tmp_path / "LOG_KAYAK.alog.gz")
    assert detect_format(packed) == "alog"
    profile = _profile(tmp_path)
    signals = read_log(packed, profile.sources)
    _same(signals, read_log(plain, profile.sources))
    assert signals.damage is None and signals.start_ns // 10**9 == LOGSTART_NS // 10**9
    listed = inventory(packed)[0]
    assert [(t.name, t.count) for t in listed.topics] == \
        [(t.name, t.count) for t in inventory(plain)[0].topics]
    said = log_identity(packed, "alog")
    assert said is not None and said.vehicle == "moos-kayak"


def test_a_compressed_alog_cut_short_or_damaged_is_read_up_to_the_damage(tmp_path):
    plain = _write_alog(tmp_path / "LOG_KAYAK.alog")
    whole = gzip.compress(plain.read_bytes() * 40, mtime=0)      # many blocks of stream
    profile = _profile(tmp_path)
    cut = tmp_path / "cut.alog.gz"
    cut.write_bytes(whole[:len(whole) // 2])
    signals = read_log(cut, profile.sources)
    assert signals.damage is not None and "ends early" in signals.damage.reason
    thrust = signals.series["thruster_0"]
    assert 0 < len(thrust) < 40 * len(read_log(plain, profile.sources).series["thruster_0"])
    broken = bytearray(whole)
    broken[len(whole) // 2: len(whole) // 2 + 64] = bytes(64)
    damaged = tmp_path / "damaged.alog.gz"
    damaged.write_bytes(bytes(broken))
    signals = read_log(damaged, profile.sources)
    assert signals.damage is not None and "damaged" in signals.damage.reason
    assert len(signals.series["thruster_0"]) > 0
    header_only = tmp_path / "header.alog.gz"
    header_only.write_bytes(whole[:12])          # the gzip header and no data at all
    with pytest.raises(LogError):
        read_log(header_only, profile.sources)


def test_a_compressed_csv_log_reads_as_the_plain_one(tmp_path, make_log):
    plain = make_log("paper-normal", 11, "csv")
    packed = _gzip(plain, tmp_path / "dive.csv.gz")
    assert detect_format(packed) == "csv"
    profile = load_profile(Path("twin_burger"))
    _same(read_log(packed, profile.sources), read_log(plain, profile.sources))
    cut = tmp_path / "cut.csv.gz"
    cut.write_bytes(packed.read_bytes()[: packed.stat().st_size // 2])
    signals = read_log(cut, profile.sources)
    assert signals.damage is not None and "ends early" in signals.damage.reason


def test_a_compressed_binary_log_is_not_taken_for_one_this_tool_reads(tmp_path, make_log):
    packed = _gzip(make_log("paper-normal", 11, "bag"), tmp_path / "dive.bag.gz")
    with pytest.raises(LogError, match="not a log this tool reads"):
        detect_format(packed)


def test_an_audit_judges_compressed_runs_and_lists_a_damaged_one(tmp_path, make_log):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    _gzip(make_log("paper-normal", 11, "alog"), fleet / "LOG_A.alog.gz")
    shutil.copy(make_log("paper-flow-sensor-covered", 11, "alog"), fleet / "LOG_B.alog")
    (fleet / "LOG_C.alog.gz").write_bytes(b"\x1f\x8b\x08\x00 damaged beyond reading")
    result = CliRunner().invoke(app, ["audit", str(fleet), "--output", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    with (tmp_path / "out" / "audit.csv").open() as stream:
        rows = {Path(row["log"]).name: row for row in csv.DictReader(stream)}
    assert set(rows) == {"LOG_A.alog.gz", "LOG_B.alog", "LOG_C.alog.gz"}
    assert rows["LOG_A.alog.gz"]["verdict"] == "normal"
    assert rows["LOG_B.alog"]["component"] == "flow_sensor"
    assert rows["LOG_C.alog.gz"]["error"]
