"""The columnar ULog decoder against pyulog, field by field, on a log packed here to the
ULog specification with what PX4 logs carry: every primitive type, arrays, nested types and
arrays of them, padding in the middle and at the end, two instances of one topic, text
messages, sync markers, a dropout, then damage: a data message of the wrong size, zeroed
bytes up to a sync marker, an id nothing subscribed, and a cut last message."""

import struct
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from adapters import read_log
from adapters.ulog_decode import SYNC, AppendedData, decode_ulog

FORMATS = {
    "vec3": "float x;float y;float z;",
    "point": "uint64_t timestamp;vec3 p;",
    "wheel": "int16_t speed;uint8_t[2] _padding0;vec3 axis;",
    "sample": ("uint64_t timestamp;int8_t a;uint8_t b;int16_t c;uint16_t d;int32_t e;"
               "uint32_t f;int64_t g;double h;float[3] q;bool ok;char letter;"
               "uint8_t[3] _padding1;vec3 pos;wheel[2] wheels;uint8_t[5] _padding2;"),
}
SAMPLE = struct.Struct("<QbBhHiIqd3f??3x3fh2x3fh2x3f")          # without the last padding


def message(kind: str, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def sample(msg_id: int, time_us: int, i: int) -> bytes:
    values = SAMPLE.pack(time_us, -i % 100, i % 200, -i, i * 3, -i * 1000, i * 7, -(i << 33),
                         i / 7, i * 0.5, -i * 0.25, 1.5, bool(i % 2), i % 2 == 0, i * 1.0,
                         i * 2.0, i * 3.0, i, -1.0, 0.0, 1.0, -i, 0.5, 0.25, 0.125)
    return message("D", struct.pack("<H", msg_id) + values)     # trailing padding not logged


def build(flags: bytes = bytes(40), damaged: bool = False) -> bytes:
    parts = [b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 1_000_000), message("B", flags)]
    parts += [message("F", f"{name}:{body}".encode()) for name, body in FORMATS.items()]
    key = b"char[5] sys_name"
    parts.append(message("I", bytes([len(key)]) + key + b"ROVER"))
    parts += [message("A", struct.pack("<BH", 0, 3) + b"sample"),
              message("A", struct.pack("<BH", 1, 7) + b"sample"),
              message("A", struct.pack("<BH", 0, 9) + b"point")]
    for i in range(400):
        time_us = 2_000_000 + i * 10_000
        parts.append(sample(3 if i % 3 else 7, time_us, i))
        parts.append(message("D", struct.pack("<HQ3f", 9, time_us, i, i, i)))
        if i % 50 == 0:
            parts.append(message("S", SYNC))
            parts.append(message("L", struct.pack("<BQ", ord("6"), time_us) + f"step {i}".encode()))
        if i == 120:
            parts.append(message("O", struct.pack("<H", 35)))
        if damaged and i == 200:
            parts.append(message("D", struct.pack("<H", 3) + bytes(10)))      # too short
            parts.append(bytes(64))                                            # zeroed bytes
            parts.append(message("S", SYNC))
            parts.append(message("D", struct.pack("<H", 42) + bytes(8)))     # nobody's id
    if damaged:
        parts.append(sample(3, 9_000_000, 999)[:-7])                          # cut short
    return b"".join(parts)


def pyulog_of(path: Path) -> ULog:
    return ULog(str(path), disable_str_exceptions=True)


@pytest.mark.parametrize("damaged", [False, True])
def test_every_field_matches_pyulog(tmp_path, damaged, capsys):
    path = tmp_path / "log.ulg"
    path.write_bytes(build(damaged=damaged))
    reference = pyulog_of(path)
    capsys.readouterr()                           # pyulog prints about the damage
    decoded = decode_ulog(path.read_bytes(), None)
    assert len(reference.data_list) == sum(len(v) for v in decoded.topics.values()) == 3
    for data in reference.data_list:
        [mine] = [i for i in decoded.topics[data.name] if i.multi_id == data.multi_id]
        assert list(mine.columns) == list(data.data)
        for name, values in data.data.items():
            assert mine.columns[name].dtype == values.dtype, name
            assert np.array_equal(mine.columns[name], values), name
    assert "wheels[1].axis.z" in decoded.topics["sample"][0].columns
    assert "_padding1[2]" in decoded.topics["sample"][0].columns      # kept, as pyulog does
    assert not any(n.startswith("_padding2") for n in decoded.topics["sample"][0].columns)
    assert decoded.logged == [(int(m.timestamp), m.message, int(m.log_level))
                              for m in reference.logged_messages]
    assert decoded.dropouts_ms == [d.duration for d in reference.dropouts] == [35]
    assert (decoded.start_us, decoded.last_us) == (reference.start_timestamp,
                                                   reference.last_timestamp)
    assert decoded.corrupt == reference.file_corruption == damaged
    assert (decoded.cut_at is not None) == damaged


def test_only_wanted_topics_are_decoded(tmp_path):
    decoded = decode_ulog(build(), {"point"})
    assert list(decoded.topics) == ["point"]
    assert decoded.topics["point"][0].columns["p.x"].size == 400


def test_appended_data_is_left_to_pyulog(tmp_path):
    flags = bytearray(40)
    flags[8] = 1                                   # incompat: data appended
    with pytest.raises(AppendedData):
        decode_ulog(build(bytes(flags)), None)
    path = tmp_path / "appended.ulg"
    path.write_bytes(build(bytes(flags)))
    from adapters.ulog import decoded_ulog

    assert decoded_ulog(path, {"point"}).topics["point"][0].columns["p.x"].size == 400


def test_simulated_log_reads_as_pyulog_reads_it(make_log, profile):
    log = make_log("paper-flow-sensor-covered", 31, "ulog")
    signals = read_log(log, profile.sources)
    reference = ULog(str(log), message_name_filter_list=sorted(
        profile.sources["ulog"].topics - {"logging"}))
    counts = {d.name: d.data["timestamp"].size for d in reference.data_list}
    assert signals.messages_read == sum(counts.values()) + len(reference.logged_messages)
