"""The no-DVL BlueROV2 profiles on the real ArduSub logs of ../shared/data/ardusub
(clydemcqueen/ardusub_log_tools, MIT): every signal resolves, the operating time found is the
armed time pymavlink reads from the same logs, and train and diagnose accept them."""

from pathlib import Path

import pytest
from helpers import diagnose_json
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
DATA = SHARED_DATA / "ardusub"
LOGS = ["small.tlog", "small.BIN", "pymavlink_bug.tlog"]
pytestmark = [pytest.mark.shared_data("ardusub"), pytest.mark.slow]


def _armed_seconds(log: Path) -> float:
    """Armed time as pymavlink reads it: the vehicle's HEARTBEAT armed bit (tlog), or the
    ARM records (DataFlash, whose logging starts armed)."""
    from pymavlink import DFReader, mavutil

    if log.suffix == ".BIN":
        reader = DFReader.DFReader_binary(str(log), zero_time_base=True)
        first = reader.recv_match(type=["RCOU"]).TimeUS
        reader.rewind()
        disarm = reader.recv_match(type=["ARM"], condition="ARM.ArmState == 0")
        return (disarm.TimeUS - first) / 1e6
    connection = mavutil.mavlink_connection(str(log))
    armed_since, total = None, 0.0
    while (message := connection.recv_match(type="HEARTBEAT")) is not None:
        if message.type != 12:                      # the submarine, not the ground station
            continue
        armed = bool(message.base_mode & 128)
        if armed and armed_since is None:
            armed_since = message._timestamp
        elif not armed and armed_since is not None:
            total += message._timestamp - armed_since
            armed_since = None
    return total


@pytest.mark.parametrize("profile", ["bluerov2_standard", "bluerov2_heavy"])
@pytest.mark.parametrize("name", LOGS)
def test_every_signal_resolves(profile, name):
    result = runner.invoke(app, ["inspect", str(DATA / name), "--profile", profile])
    assert result.exit_code == 0 and "MISSING" not in result.stdout, result.stdout


@pytest.fixture(scope="module")
def real_model(tmp_path_factory):
    output = tmp_path_factory.mktemp("model") / "rov"
    result = runner.invoke(app, ["train", str(DATA / "small.tlog"), str(DATA / "small.BIN"),
                                 "--holdout", str(DATA / "small.BIN"), "--profile",
                                 "bluerov2_standard", "--output", str(output),
                                 "--iterations-scale", "0.02", "--keep-unskilled",
                                 "--predictor", "network", "--predictor", "linear"])
    assert result.exit_code in (0, 1) and (output / "model.json").is_file(), result.output
    assert "are logged at 2.0 Hz" in result.output             # QGroundControl's rate
    return output


@pytest.mark.parametrize("name", ["small.tlog", "small.BIN"])
def test_operating_time_is_the_armed_time(real_model, name):
    _, report = diagnose_json(DATA / name, "--profile", "bluerov2_standard", "--model",
                              str(real_model))
    operating = report["duration_s"] - report["not_operating_s"]
    assert operating == pytest.approx(_armed_seconds(DATA / name), abs=1.2)


def test_a_log_never_armed_is_not_judged(real_model):
    result = runner.invoke(app, ["diagnose", str(DATA / "pymavlink_bug.tlog"), "--profile",
                                 "bluerov2_standard", "--model", str(real_model)])
    assert result.exit_code == 2 and "never operates" in result.output


def _without_records(log: Path, name: str, target: Path) -> Path:
    """``log`` with every DataFlash record of message ``name`` cut out (an older firmware's
    log, which keeps arming only in EV events). Record lengths come from the FMT records."""
    data, kept, at, lengths = log.read_bytes(), bytearray(), 0, {128: (89, "FMT")}
    while at + 3 <= len(data) and data[at:at + 2] == b"\xa3\x95":
        kind = data[at + 2]
        if kind == 128:
            fmt_type, fmt_length = data[at + 3], data[at + 4]
            lengths[fmt_type] = (fmt_length, data[at + 5:at + 9].rstrip(b"\0").decode())
        length, message = lengths[kind]
        if message != name:
            kept += data[at:at + length]
        at += length
    assert at == len(data), "the test's record walk lost its way"
    target.write_bytes(bytes(kept))
    return target


def test_arming_is_read_from_ev_events_where_a_log_has_no_arm_records(real_model, tmp_path):
    older = _without_records(DATA / "small.BIN", "ARM", tmp_path / "no_arm.BIN")
    _, report = diagnose_json(older, "--profile", "bluerov2_standard", "--model",
                              str(real_model))
    assert report["duration_s"] - report["not_operating_s"] == pytest.approx(
        _armed_seconds(DATA / "small.BIN"), abs=1.2)
    assert any("operating from EV.Id (no ARM message" in note for note in report["notes"])
    shown = runner.invoke(app, ["inspect", str(older), "--profile", "bluerov2_standard"])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout
    assert "operating    EV Id" in shown.stdout


def test_a_log_the_default_profile_does_not_fit_names_the_profiles_that_do():
    result = runner.invoke(app, ["diagnose", str(DATA / "small.BIN")])
    assert result.exit_code == 2
    line, = result.output.strip().splitlines()
    assert "no messages for signal(s) flow" in line
    fitting = line.split("the shipped profiles that fit this log: ")[1]
    assert "bluerov2_standard" in fitting and "twin_burger" not in fitting


def test_inspect_gives_the_rate_between_samples_and_how_much_of_the_log_it_covers():
    text = runner.invoke(app, ["inspect", str(DATA / "small.BIN"), "--profile",
                               "bluerov2_standard"]).stdout
    assert "count mean rate" in text
    assert ("    ok       motor_1      RCOU C1  (237 samples, 10.0 Hz between samples: about "
            "24 s of the log's 136 s;") in text
