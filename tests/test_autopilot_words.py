"""What the vehicle's own software said during a log: ArduPilot's texts and error records
read from real DataFlash and telemetry bytes (checked against pymavlink's reading of the same
files), kept only while the vehicle operated, grouped, and lined up with the verdict."""

import json
import shutil
import struct
from pathlib import Path

import numpy as np
import pandas as pd
import pypdf
import pytest
from helpers import diagnose_json
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega
from test_mcap_export import read_back
from typer.testing import CliRunner

from adapters import read_log
from adapters.autopilot_messages import error_text, ulog_messages
from adapters.signals import AutopilotMessage
from auvdiag_cli.cli import app
from auvdiag_cli.engine.autopilot_words import is_alarm, said_while_operating
from auvdiag_cli.fuzz.mutations import mutate
from auvdiag_cli.vehicle.profile import load_profile
from auvdiag_errors import AuvdiagError

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"
ERR_TYPE = 200
THRUST_LOSS = "Potential Thrust Loss (3)"


def _dataflash_record(type_id: int, layout: str, *values: object) -> bytes:
    return b"\xa3\x95" + bytes([type_id]) + struct.pack("<" + layout, *values)


def _fmt(type_id: int, name: str, layout: str, fmt: str, columns: str) -> bytes:
    length = 3 + struct.calcsize("<" + layout)
    return _dataflash_record(128, "BB4s16s64s", type_id, length, name.encode(),
                             fmt.encode(), columns.encode())


def _msg_type(data: bytes) -> int:
    """The type id the log's FMT gives MSG."""
    at = data.find(b"MSG\0")
    return data[at - 2]


def _with_dataflash_words(source: Path, target: Path, words: list[tuple[float, str]],
                          errors: list[tuple[float, int, int]]) -> Path:
    """``source`` with MSG texts and ERR records (an FMT for ERR first) appended."""
    data = source.read_bytes()
    msg = _msg_type(data)
    tail = _fmt(ERR_TYPE, "ERR", "QBB", "QBB", "TimeUS,Subsys,ECode")
    tail += b"".join(_dataflash_record(msg, "Q64s", round(t * 1e6), text.encode())
                     for t, text in words)
    tail += b"".join(_dataflash_record(ERR_TYPE, "QBB", round(t * 1e6), subsystem, code)
                     for t, subsystem, code in errors)
    target.write_bytes(data + tail)
    return target


def _first_record_us(path: Path) -> int:
    log = mavutil.mavlink_connection(str(path))
    first = log.recv_match(type="RCOU")
    return int(first.TimeUS)


def test_dataflash_texts_and_error_records_read_as_pymavlink_reads_them(tmp_path):
    log = _with_dataflash_words(
        SAMPLES / "mission-large-ccw.bin", tmp_path / "words.bin",
        [(40.0, THRUST_LOSS), (41.0, THRUST_LOSS), (50.0, "EKF3 IMU0 is using GPS")],
        [(40.0, 25, 1), (60.0, 16, 2), (70.0, 16, 0)])
    signals = read_log(log, load_profile(Path("twin_burger")).sources)
    mine = [(m.time_ns // 1000, m.text, m.severity) for m in signals.autopilot_messages]
    reference = mavutil.mavlink_connection(str(log))
    theirs = []
    while (record := reference.recv_match(type=["MSG", "ERR"])) is not None:
        if record.get_type() == "MSG":
            theirs.append((record.TimeUS, record.Message, None))
        else:
            theirs.append((record.TimeUS, error_text(record.Subsys, record.ECode),
                           6 if record.ECode == 0 else 3))
    assert sorted(mine, key=lambda m: m[0]) == sorted(theirs, key=lambda m: m[0])
    assert (40_000_000, "ERR thrust loss check: occurred", 3) in mine
    assert (60_000_000, "ERR EKF check: bad variance", 3) in mine
    assert (70_000_000, "ERR EKF check: cleared", 6) in mine


def _statustext(mav: ardupilotmega.MAVLink, severity: int, text: str) -> bytes:
    return mav.statustext_encode(severity, text.encode()).pack(mav)


def test_a_telemetry_logs_statustext_is_read_with_its_severity(tmp_path):
    source = SAMPLES / "mission-fast-ccw.tlog"
    first_us = struct.unpack(">Q", source.read_bytes()[:8])[0]
    mav = ardupilotmega.MAVLink(None, srcSystem=1, srcComponent=1)
    said = [(30.0, ardupilotmega.MAV_SEVERITY_EMERGENCY, THRUST_LOSS),
            (35.0, ardupilotmega.MAV_SEVERITY_INFO, "Mission: 2 WP")]
    log = tmp_path / "words.tlog"
    log.write_bytes(source.read_bytes() + b"".join(
        struct.pack(">Q", first_us + round(t * 1e6)) + _statustext(mav, severity, text)
        for t, severity, text in said))
    signals = read_log(log, load_profile(Path("twin_burger")).sources)
    mine = [(m.time_ns // 1000, m.text, m.severity) for m in signals.autopilot_messages]
    reference = mavutil.mavlink_connection(str(log))
    theirs = []
    while (record := reference.recv_match(type="STATUSTEXT")) is not None:
        theirs.append((round(record._timestamp * 1e6), record.text, record.severity))
    assert [(text, severity) for _, text, severity in mine] == [
        (text, severity) for _, text, severity in theirs]
    assert all(abs(a[0] - b[0]) <= 1 for a, b in zip(mine, theirs, strict=True))
    assert (first_us + 30_000_000, THRUST_LOSS, 0) in mine


def test_only_trouble_said_while_operating_is_kept_and_repeats_are_grouped():
    messages = [AutopilotMessage(0, "PreArm: Battery below minimum", 2),   # before arming
                AutopilotMessage(int(12e9), THRUST_LOSS),                  # no severity: words
                AutopilotMessage(int(13e9), THRUST_LOSS),
                AutopilotMessage(int(14e9), "Mission: 3 WP"),
                AutopilotMessage(int(15e9), "EKF Failsafe Cleared", 2),    # clears: no trouble
                AutopilotMessage(int(20.5e9), "Crash: Disarming"),         # as it disarms
                AutopilotMessage(int(40e9), "Leak Detected", 2)]           # long after
    time_s = np.arange(0.0, 50.0, 0.1)
    operating = (time_s >= 10.0) & (time_s < 20.0)
    said = said_while_operating(messages, 0, time_s, operating)
    assert said is not None
    assert [(a.text, a.first_s, a.last_s, a.times) for a in said.alarms] == [
        (THRUST_LOSS, 12.0, 13.0, 2), ("Crash: Disarming", 20.5, 20.5, 1)]
    assert said.other_messages == 2
    assert said_while_operating([], 0, time_s, operating) is None
    assert not is_alarm(AutopilotMessage(0, "EKF3 IMU0 is using GPS", 6))
    assert is_alarm(AutopilotMessage(0, "Lost manual control"))
    # ArduCopter's thrust-loss check names a motor by its number: lined up with the verdict's.
    assert said.describe(True, 11.0, "motor_3").endswith(
        "Crash: Disarming\" 9.5 s after the onset (20.5 s): the autopilot's thrust-loss check "
        "names motor 3 too")
    assert said.describe(True, 11.0, "motor_1").endswith("names motor 3, not motor 1")
    assert said.describe(True, 11.0, None).endswith("after the onset (20.5 s)")
    assert ulog_messages([(5, "Motor failure detected", ord("2"))]) == [
        AutopilotMessage(5000, "Motor failure detected", 2)]


def test_a_normal_verdict_says_what_the_autopilot_reported_that_it_did_not_find(tmp_path):
    log = _with_dataflash_words(SAMPLES / "mission-large-ccw.bin", tmp_path / "normal.bin",
                                [(80.0, THRUST_LOSS), (81.0, THRUST_LOSS)], [(80.0, 25, 1)])
    at_s = 80.0 - _first_record_us(log) / 1e6
    result = CliRunner().invoke(app, ["diagnose", str(log), "--json", str(tmp_path / "d.json"),
                                      "--pdf", str(tmp_path / "d.pdf"),
                                      "--mcap", str(tmp_path / "d.mcap")])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "d.json").read_text())
    assert report["verdict"] == "normal"
    autopilot = report["autopilot"]
    assert [(a["text"], a["times"]) for a in autopilot["alarms"]] == [
        (THRUST_LOSS, 2), ("ERR thrust loss check: occurred", 1)]
    assert autopilot["alarms"][0]["first_s"] == pytest.approx(at_s, abs=1e-3)
    said = (f'reported trouble this diagnosis did not find: "{THRUST_LOSS}" at {at_s:.1f} s, '
            f"2 times to {at_s + 1:.1f} s")
    assert autopilot["summary"].startswith(said)
    assert result.stdout.splitlines()[2].startswith(f"  autopilot: {said}")
    pages = [" ".join(page.extract_text().split())
             for page in pypdf.PdfReader(tmp_path / "d.pdf").pages]
    assert f"Autopilot said: {said}" in pages[0]
    # The time-history pages mark when it said it.
    assert all("the autopilot reported trouble" in page for page in pages[1:])
    # `inspect` says it over the whole log, before any model is chosen.
    shown = CliRunner().invoke(app, ["inspect", str(log)])
    assert (f'  autopilot reported trouble: "{THRUST_LOSS}" at 80.0 s, 2 times to 81.0 s; '
            '"ERR thrust loss check: occurred" at 80.0 s') in shown.stdout.splitlines()
    # In Foxglove's Log panel, at the time the autopilot first said it, on the log's clock.
    messages, _ = read_back(tmp_path / "d.mcap")
    events = {body["message"]: t for t, body in messages["/auvdiag/events"]}
    assert events[f"the autopilot said: {THRUST_LOSS} (2 times to {at_s + 1:.1f} s)"] == (
        pytest.approx(80e9, abs=1e6))


def test_a_fault_lines_the_autopilots_words_up_with_its_onset(tmp_path):
    expected = json.loads((SAMPLES / "mission-yaw-rate-sensor-dead-bin.expected.json")
                          .read_text())
    source = tmp_path / "dead.bin"
    shutil.copy(SAMPLES / "mission-yaw-rate-sensor-dead-bin.bin", source)
    start_s = _first_record_us(source) / 1e6
    said_at = start_s + expected["onset_s"] + 1.5
    log = _with_dataflash_words(source, tmp_path / "words.bin",
                                [(said_at, "Gyro 1 unhealthy")], [])
    code, report = diagnose_json(log)
    assert code == 1 and report["component"] == expected["component"]
    assert report["autopilot"]["summary"] == (
        f'"Gyro 1 unhealthy" 1.5 s after the onset ({expected["onset_s"] + 1.5:.1f} s)')


def test_an_audit_row_lists_the_trouble_the_autopilot_reported(tmp_path):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    _with_dataflash_words(SAMPLES / "mission-large-ccw.bin", fleet / "said.bin",
                          [(80.0, THRUST_LOSS)], [(90.0, 27, 1)])
    shutil.copy(SAMPLES / "mission-large-ccw.bin", fleet / "quiet.bin")
    result = CliRunner().invoke(app, ["audit", str(fleet), "--output", str(tmp_path / "out"),
                                      "--jobs", "1"])
    assert result.exit_code == 0, result.output
    rows = pd.read_csv(tmp_path / "out" / "audit.csv").set_index("log")
    assert rows.loc[str(fleet / "said.bin"), "autopilot_alarms"] == (
        f"{THRUST_LOSS};ERR leak failsafe: occurred")
    assert pd.isna(rows.loc[str(fleet / "quiet.bin"), "autopilot_alarms"])
    # The fleet summary lists the log whose autopilot reported what the diagnosis did not find.
    summary = " ".join(" ".join(page.extract_text().split()) for page in
                       pypdf.PdfReader(tmp_path / "out" / "audit.pdf").pages)
    assert ("Trouble the autopilot reported that the diagnosis did not find said.bin (normal): "
            f"{THRUST_LOSS}; ERR leak failsafe: occurred") in summary
    assert "quiet.bin (normal)" not in summary


@pytest.mark.parametrize("suffix", ["bin", "tlog"])
def test_damaged_words_are_read_or_refused_in_one_line(tmp_path, suffix):
    """The texts and error records come from untrusted bytes: damaged anywhere (the fuzzer's
    mutations), a log is read or refused as a log error, never crashes the reader."""
    if suffix == "bin":
        source = _with_dataflash_words(SAMPLES / "mission-large-ccw.bin", tmp_path / "w.bin",
                                       [(t, THRUST_LOSS) for t in (5.0, 6.0)],
                                       [(t, 25, 1) for t in (5.0, 6.0)])
    else:
        source = SAMPLES / "mission-fast-ccw.tlog"
    data = source.read_bytes()
    # The words sit at the file's end (bin) or its start (the tlog's banner): damage there.
    region = data[-2000:] if suffix == "bin" else data[:20000]
    sources = load_profile(Path("twin_burger")).sources
    read = 0
    for seed in range(150):
        damaged, _ = mutate(region, seed)
        log = tmp_path / f"damaged.{suffix}"
        log.write_bytes(data[:-2000] + damaged if suffix == "bin" else damaged + data[20000:])
        try:
            signals = read_log(log, sources)
        except AuvdiagError:
            continue
        read += 1
        assert all(isinstance(m.text, str) for m in signals.autopilot_messages)
    assert read > 20


def test_train_and_calibrate_warn_of_a_normal_log_the_autopilot_found_trouble_in(tmp_path):
    from auvdiag_cli import api
    from auvdiag_cli.jobs.training_logs import read_for_training

    log = _with_dataflash_words(SAMPLES / "mission-large-ccw.bin", tmp_path / "said.bin",
                                [(80.0, "Leak Detected")], [])
    profile = load_profile(Path("twin_burger"))
    said: list[str] = []
    read_for_training(log, profile, said.append)
    at_s = 80.0 - _first_record_us(log) / 1e6
    warning = (f'warning: said.bin: the autopilot reported trouble while it operated: "Leak '
               f'Detected" at {at_s:.1f} s: a log given as normal should hold no fault '
               "(--healthy keeps only a log's healthy part)")
    assert said == [warning]
    # Its healthy part alone holds none.
    said.clear()
    read_for_training(log, profile, said.append, part=(None, 70_000_000_000))
    assert said == []
    calibrating: list[str] = []
    api.calibrate([log, SAMPLES / "mission-large-ccw.bin"], profile,
                  api.load_model(None, profile), progress=calibrating.append)
    assert calibrating.count(warning) == 1


def test_a_px4_logs_messages_keep_their_level_and_reach_the_report(make_log, tmp_path):
    """PX4 logs its messages with a syslog level ('2' critical); the simulated dive's own
    (its segment markers) are informational, so only the critical one is trouble."""
    source = make_log("paper-normal", 11, "ulog")
    profile = load_profile()
    start_ns = read_log(source, profile.sources).start_ns
    said_us = start_ns // 1000 + 50_000_000
    text = b"Motor failure detected"
    payload = bytes([ord("2")]) + struct.pack("<Q", said_us) + text
    log = tmp_path / "said.ulg"
    log.write_bytes(source.read_bytes() + struct.pack("<HB", len(payload), ord("L")) + payload)
    messages = read_log(log, profile.sources).autopilot_messages
    assert (said_us * 1000, "Motor failure detected", 2) in [
        (m.time_ns, m.text, m.severity) for m in messages]
    assert all(m.severity == 6 for m in messages if m.text != "Motor failure detected")
    code, report = diagnose_json(log)
    assert code == 0
    assert [(a["text"], a["severity"], a["first_s"]) for a in report["autopilot"]["alarms"]] == [
        ("Motor failure detected", 2, 50.0)]
