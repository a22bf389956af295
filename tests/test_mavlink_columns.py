"""The columnar MAVLink and DataFlash decoders against pymavlink's own per-message decoding,
on logs written by pymavlink (tlog) and by the DataFlash record layout (bin)."""

import struct

import numpy as np
import pytest
from pymavlink import DFReader, mavutil
from pymavlink.dialects.v10 import ardupilotmega as mavlink1
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from typer.testing import CliRunner

from adapters.mavlink import _message_classes, _message_names
from adapters.mavlink_columns import decode_dataflash, decode_mavlink
from adapters.mavlink_scan import index_file


def pymavlink_tlog(path, type_name):
    """(times µs, messages) of one type, the way pymavlink reads a tlog."""
    reader = mavutil.mavlink_connection(str(path), robust_parsing=True)
    times, messages = [], []
    while (message := reader.recv_match(type=type_name)) is not None:
        times.append(round(message._timestamp * 1e6))
        messages.append(message)
    return times, messages


def assert_rows_equal(rows, messages, fields):
    assert len(rows) == len(messages)
    for field in fields:
        expected = [getattr(m, field) for m in messages]
        got = rows[field]
        if got.dtype.kind == "S":
            assert [g.decode() for g in got.tolist()] == expected, field
        else:
            np.testing.assert_array_equal(got, np.array(expected, dtype=got.dtype), field)


@pytest.mark.parametrize("type_name", ["SERVO_OUTPUT_RAW", "NAMED_VALUE_FLOAT", "ATTITUDE",
                                       "STATUSTEXT", "HEARTBEAT"])
def test_simulated_tlog_decodes_as_pymavlink_does(make_log, type_name):
    path = make_log("paper-normal", 21, "tlog")
    message_class = _message_classes()[type_name]
    times, rows, failed = decode_mavlink(index_file(path, "tlog", _message_names()),
                                         message_class)
    expected_times, messages = pymavlink_tlog(path, type_name)
    assert failed == 0 and len(messages) >= (1 if type_name == "STATUSTEXT" else 100)
    assert times.tolist() == expected_times
    assert_rows_equal(rows, messages, message_class.fieldnames)


def write_mixed_tlog(path, corrupt_one=False):
    """MAVLink 1 and 2 frames interleaved; MAVLink 2 drops the payload's trailing zeros,
    which the short NAMED_VALUE_FLOAT names and zero servo channels produce."""
    v1 = mavlink1.MAVLink(None, srcSystem=1, srcComponent=1)
    v2 = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    records = []
    for i in range(40):
        mav, module = (v1, mavlink1) if i % 3 == 0 else (v2, mavlink2)
        servo = module.MAVLink_servo_output_raw_message(i * 1000, 0, 1100 + i, 1900 - i,
                                                         *([0] * 6))
        named = module.MAVLink_named_value_float_message(i, b"FLOW" if i % 2 else b"X",
                                                         0.01 * i - 0.2)
        for message in (servo, named):
            records.append(struct.pack(">Q", 1_795_000_000_000_000 + i * 100_000 + len(
                records)) + message.pack(mav))
    if corrupt_one:
        damaged = bytearray(records[8])        # SERVO_OUTPUT_RAW, MAVLink 2
        damaged[20] ^= 0x55                     # a payload byte: the CRC no longer matches
        records[8] = bytes(damaged)
    path.write_bytes(b"".join(records))
    return path


@pytest.mark.parametrize("type_name", ["SERVO_OUTPUT_RAW", "NAMED_VALUE_FLOAT"])
def test_mavlink1_and_truncated_mavlink2_frames_decode_as_pymavlink_does(tmp_path, type_name):
    path = write_mixed_tlog(tmp_path / "mixed.tlog")
    raw = path.read_bytes()
    assert raw.count(b"\xfe") >= 14 and len(raw) < 80 * (8 + 12 + 37)  # v1 and short v2
    message_class = _message_classes()[type_name]
    times, rows, failed = decode_mavlink(index_file(path, "tlog", _message_names()),
                                         message_class)
    expected_times, messages = pymavlink_tlog(path, type_name)
    assert failed == 0 and len(messages) == 40
    assert times.tolist() == expected_times
    assert_rows_equal(rows, messages, message_class.fieldnames)


def test_a_frame_with_a_bad_checksum_is_left_out_like_pymavlink_does(tmp_path):
    path = write_mixed_tlog(tmp_path / "damaged.tlog", corrupt_one=True)
    message_class = _message_classes()["SERVO_OUTPUT_RAW"]
    _, rows, failed = decode_mavlink(index_file(path, "tlog", _message_names()),
                                         message_class)
    _, messages = pymavlink_tlog(path, "SERVO_OUTPUT_RAW")
    assert failed == 1 and len(rows) == 39 == len(messages)
    assert_rows_equal(rows, messages, message_class.fieldnames)


def test_a_damaged_tlog_frame_becomes_a_note_in_the_analysis(tmp_path, make_log, profile):
    from auvdiag_cli.engine.ingest import ingest

    path = make_log("paper-normal", 21, "tlog")
    index = index_file(path, "tlog", _message_names())
    servo = index.offsets[index.of_type(_message_classes()["SERVO_OUTPUT_RAW"].id)]
    source = bytearray(path.read_bytes())
    source[servo[500] + 8 + 10 + 6] ^= 0xFF       # a payload byte of the 501st
    damaged = tmp_path / "flipped.tlog"
    damaged.write_bytes(bytes(source))
    log = ingest(damaged, profile)
    assert "1 MAVLink frames failed their checksum and were left out" in log.signals.notes
    assert len(log.signals.series["thruster_0"]) == servo.size - 1


FMT = struct.Struct("<BB4s16s64s")
TYPES = "QcCeELZahiqdBfnN"              # 16: all a FMT record holds
LAYOUT = "<QhHiIi64s32hhiqdBf4s16s"
COLUMNS = "TimeUS,Cc,CC,Ce,CE,Lat,Text,Arr,H,I,Q,D,UB,F,Nm,Lbl"


def test_dataflash_types_and_multipliers_decode_as_pymavlink_does(tmp_path):
    rng = np.random.default_rng(3)
    body = struct.Struct(LAYOUT)
    records = [b"\xa3\x95\x80" + FMT.pack(128, 89, b"FMT", b"BBnNZ",
                                          b"Type,Length,Name,Format,Columns"),
               b"\xa3\x95\x80" + FMT.pack(40, 3 + body.size, b"TEST", TYPES.encode(),
                                          COLUMNS.encode())]
    for i in range(50):
        values = (1_000_000 + 2500 * i, int(rng.integers(-3000, 3000)), 1234 + i,
                  -98765 + i, 4_000_000 + i, int(rng.integers(-900_000_000, 900_000_000)),
                  f"line {i}".encode(), *rng.integers(-500, 500, 32).tolist(), -7 * i,
                  123456 * i, -(2**40) + i, float(rng.normal()), i, float(rng.normal()),
                  b"abc", b"label\0junk")
        records.append(b"\xa3\x95\x28" + body.pack(*values))
    path = tmp_path / "types.bin"
    path.write_bytes(b"".join(records))

    times, rows, divisors = decode_dataflash(index_file(path, "bin"), 40)
    reader = DFReader.DFReader_binary(str(path), zero_time_base=True)
    messages = []
    while (message := reader.recv_match(type="TEST")) is not None:
        messages.append(message)
    assert len(messages) == 50 and times.tolist() == [m.TimeUS for m in messages]
    for column in COLUMNS.split(","):
        expected = [getattr(m, column) for m in messages]
        got = rows[column]
        if column in divisors:
            np.testing.assert_array_equal(got / divisors[column], expected, column)
        elif got.dtype.kind == "S":
            assert [g.split(b"\0")[0].decode() for g in got.tolist()] == expected, column
        else:
            np.testing.assert_array_equal(got, np.array(expected), column)


def test_inspect_counts_the_frames_that_fail_their_checksum(tmp_path, make_log):
    from auvdiag_cli.cli import app

    path = make_log("paper-normal", 21, "tlog")
    index = index_file(path, "tlog", _message_names())
    servo = index.offsets[index.of_type(_message_classes()["SERVO_OUTPUT_RAW"].id)]
    source = bytearray(path.read_bytes())
    for k in (100, 500):
        source[servo[k] + 8 + 10 + 6] ^= 0xFF
    damaged = tmp_path / "flipped.tlog"
    damaged.write_bytes(bytes(source))
    text = CliRunner().invoke(app, ["inspect", str(damaged)]).stdout
    assert ("  note: 2 MAVLink frames fail their checksum in the dialect this tool reads "
            "(counted above; a diagnosis leaves them out): SERVO_OUTPUT_RAW 2") in text
