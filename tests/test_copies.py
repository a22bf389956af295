"""A log named after another beside it is a copy or a dive by its content: the same bytes, a
copy cut short, or the same stretch of time (the dive recorded again) are copies, left out
of an audit with the reason; a continuation or another dive is a dive."""

import shutil
from dataclasses import replace
from pathlib import Path

from auvdiag_cli.audit.discovery import discover
from auvdiag_cli.simulator.writers import write_log

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"


def test_copies_are_left_out_with_their_reason_and_other_logs_stay_dives(tmp_path):
    original = SAMPLES / "mission-large-ccw.bin"
    shutil.copy(original, tmp_path / "run.bin")
    shutil.copy(original, tmp_path / "run.1.bin")                       # the same bytes
    (tmp_path / "run.2.bin").write_bytes(original.read_bytes()[:50_000])  # cut short
    shutil.copy(SAMPLES / "mission-yaw-rate-sensor-dead-bin.bin", tmp_path / "run.3.bin")
    found = discover([str(tmp_path)])
    assert sorted(p.name for p in found.logs) == ["run.3.bin", "run.bin"]
    why = {p.name: reason for p, reason in found.skipped}
    assert why["run.1.bin"] == "a copy of run.bin (the same bytes)"
    assert why["run.2.bin"] == "the first 50000 bytes of run.bin (a copy cut short)"


def test_the_complete_copy_stays_when_the_first_download_was_cut(tmp_path):
    data = (SAMPLES / "mission-large-ccw.bin").read_bytes()
    (tmp_path / "run.bin").write_bytes(data[:40_000])
    (tmp_path / "run.1.bin").write_bytes(data)
    found = discover([str(tmp_path)])
    assert [p.name for p in found.logs] == ["run.1.bin"]
    assert found.skipped == [(tmp_path / "run.bin",
                              "the first 40000 bytes of run.1.bin (a copy cut short)")]


def test_the_same_dive_in_another_container_is_the_same_recording(tmp_path, make_log,
                                                                   dive_cache, profile):
    shutil.copy(make_log("paper-normal", 11, "bag"), tmp_path / "dive.bag")
    shutil.copy(make_log("paper-normal", 11, "mcap"), tmp_path / "dive.1.mcap")
    later = replace(dive_cache("paper-normal", 11), start_ns=dive_cache(
        "paper-normal", 11).start_ns + 3600 * 10**9)                 # the next hour's dive
    write_log(later, profile, tmp_path / "dive.2.mcap", "mcap")
    found = discover([str(tmp_path)])
    why = {p.name: reason for p, reason in found.skipped}
    assert why["dive.1.mcap"].startswith("the same recording as dive.bag (100% of its time")
    assert sorted(p.name for p in found.logs) == ["dive.2.mcap", "dive.bag"]
