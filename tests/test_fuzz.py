"""The fuzzer: a short seeded campaign over every format finds no defect, and the harness
really tells each kind of defect from a read or a rejected log."""

import json
import subprocess
import sys
import textwrap

import pytest

from auvdiag_cli.fuzz.mutations import MUTATIONS, mutate

FORMATS = ("bag", "db3", "ros2-mcap", "mcap", "json-mcap", "protobuf-mcap", "tlog", "bin",
           "ulog", "alog", "csv", "topic-csv", "bag+words", "db3+words", "ros2-mcap+words",
           "mcap+words", "topic-csv+words", "alog.gz", "csv.gz")


def test_mutations_are_reproducible_and_damage_the_bytes():
    data = bytes(range(256)) * 64
    first, done = mutate(data, 12345)
    assert (first, done) == mutate(data, 12345)
    assert first != data and 1 <= len(done) <= 3
    for tiny in (b"", b"\x01", b"\x01\x02\x03"):        # nothing left to damage is no error
        assert all(len(mutate(tiny, seed)[0]) <= 8 * len(tiny) for seed in range(300))
    kinds = {text.split()[0] for seed in range(400) for text in mutate(data, seed)[1]}
    assert len(kinds) >= len(MUTATIONS) - 1      # every kind of damage is drawn


@pytest.mark.slow
def test_seeded_campaign_over_every_format_has_no_defect(tmp_path):
    report_path = tmp_path / "fuzz.json"
    result = subprocess.run(
        [sys.executable, "-m", "auvdiag_cli.fuzz", "--cases", "15", "--jobs", "2",
         "--json", str(report_path)], capture_output=True, text=True, timeout=600)
    report = json.loads(report_path.read_text())
    defects = {name: s["defect_cases"] for name, s in report["seeds"].items() if s["defects"]}
    assert result.returncode == 0 and not defects, (result.stderr[-2000:], defects)
    assert set(report["seeds"]) == set(FORMATS)
    assert all(s["cases"] == 15 for s in report["seeds"].values())
    totals = {kind: sum(s[kind] for s in report["seeds"].values())
              for kind in ("read", "rejected")}
    assert totals["read"] > 20 and totals["rejected"] > 20     # the damage was real
    assert max(s["peak_rss_mb"] for s in report["seeds"].values()) < 1024


def test_a_ros_seed_with_words_carries_them_and_damages_them(tmp_path):
    from adapters import read_log
    from auvdiag_cli.fuzz.seeds import simulated_seeds
    from auvdiag_cli.vehicle.profile import load_profile

    profile = load_profile()
    seeds = simulated_seeds(tmp_path, profile, ("bag", "bag+words", "topic-csv+words"))
    said = {seed.name: read_log(seed.path, profile.sources).autopilot_messages for seed in seeds}
    assert not said["bag"]
    for name in ("bag+words", "topic-csv+words"):
        texts = {m.text for m in said[name]}
        assert "/dvl_driver: DVL lost bottom lock" in texts and "PreArm: check 3" in texts
        assert {m.text for m in said[name] if m.standing} == {"battery: low voltage",
                                                               "leak: sensor"}
    assert seeds[2].storage.name.endswith("-rosout.csv")      # the words are what is damaged
    with pytest.raises(ValueError, match="only a ROS format"):
        simulated_seeds(tmp_path / "tlog", profile, ("tlog+words",))


HARNESS_SCRIPT = textwrap.dedent("""
    import json, os, signal, sys, time
    from pathlib import Path
    from auvdiag_cli.fuzz.harness import Case, Limits, run_cases
    from auvdiag_cli.fuzz.seeds import SeedLog

    def check(path, profile, model):
        kind = path.stem
        if kind == "crash":
            raise KeyError("a bug")
        if kind == "signal":
            os.kill(os.getpid(), signal.SIGSEGV)
        if kind == "hang":
            time.sleep(60)
        if kind == "memory":
            hoard = bytearray(2 << 30)
        if kind == "output":
            print("a library talking")
        return kind, ""

    folder = Path(sys.argv[1])
    cases = []
    for kind in ("read", "rejected", "crash", "signal", "hang", "memory", "output"):
        path = folder / f"{kind}.log"
        path.write_bytes(b"x" * 4096)
        cases.append(Case(SeedLog(kind, path, path), 0))
    results = run_cases(cases, None, None, Limits(time_s=3, memory_mb=256), 3, check)
    print(json.dumps({r.log: [r.outcome, r.detail] for r in results}))
""")


@pytest.mark.slow
def test_harness_sorts_every_outcome(tmp_path):
    result = subprocess.run([sys.executable, "-c", HARNESS_SCRIPT, str(tmp_path)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    outcomes = json.loads(result.stdout.strip().splitlines()[-1])
    assert {name: outcome for name, (outcome, _) in outcomes.items()} == {
        "read": "read", "rejected": "rejected", "crash": "crash", "signal": "crash",
        "hang": "hang", "memory": "memory", "output": "output"}
    assert "KeyError" in outcomes["crash"][1] and "signal 11" in outcomes["signal"][1]
    assert "a library talking" in outcomes["output"][1]


@pytest.mark.parametrize(("message", "verdict"), [
    ("{path}: damaged beyond use", "rejected"),
    ("{path}: two\nlines", "crash"),
    ("damaged, but which file?", "crash"),
])
def test_an_error_must_be_one_line_naming_the_file(monkeypatch, tmp_path, profile, message,
                                                   verdict):
    from auvdiag_cli.fuzz.harness import exercise
    from auvdiag_cli.jobs import inspect as inspection
    from auvdiag_errors import UsageError
    from models.store import load_model

    log = tmp_path / "log.bin"
    log.write_bytes(b"\xa3\x95\x80" + b"\0" * 200)

    def refuse(path, _profile):
        raise UsageError(message.format(path=path))

    monkeypatch.setattr(inspection, "inspect_log", refuse)
    outcome, detail = exercise(log, profile, load_model(None, profile.name))
    assert outcome == verdict, detail


@pytest.mark.parametrize(("fmt", "case"), [
    ("bin", 1213),    # a float turned into a signalling NaN: NumPy warned on stderr
    ("bin", 1826),    # an FMT record naming one column twice: the dtype raised ValueError
    ("bin", 4856),    # an alarm on the last sample put the onset one step after the log
    ("bin", 4963),    # an MSG format without its Message column: the marker field raised
    ("bin", 894),     # a column name damaged into "C\x13": init-profile drafted it, unparsed
    ("db3", 712),     # a damaged timestamp cell read as text: the span query raised
    ("db3", 2154),    # a record declaring a huge blob: sqlite's "out of memory" escaped
    ("db3", 6365),    # a topic name that is not UTF-8: the text conversion raised
])
def test_defects_the_campaign_found_stay_fixed(tmp_path, fmt, case):
    report_path = tmp_path / "case.json"
    result = subprocess.run(
        [sys.executable, "-m", "auvdiag_cli.fuzz", "--formats", fmt, "--first-case",
         str(case), "--cases", "1", "--jobs", "1", "--json", str(report_path)],
        capture_output=True, text=True, timeout=300)
    summary = json.loads(report_path.read_text())["seeds"][fmt]
    assert result.returncode == 0 and summary["defects"] == 0, summary["defect_cases"]


def test_a_signalling_nan_converts_quietly():
    import warnings

    import numpy as np

    from adapters.signals import FieldSource

    signalling = np.array([0x7FA00000], np.uint32).view(np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        converted = FieldSource("IMU", "GyrZ", scale=2.0).convert(signalling)
        flag = FieldSource("HEARTBEAT", "base_mode", bits=128).convert(signalling)
    assert np.isnan(converted[0]) and flag[0] in (0.0, 1.0)
