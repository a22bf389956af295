"""MCAP as the specification allows it: summaries, indexes and statistics are optional, a
summary need not repeat Channel and Schema records, chunks need not be in time order, a
topic may have several channels, unknown opcodes must be skipped. Every layout, written with
the mcap library's own writer options, gives the diagnosis the canonical layout gives."""

import struct

import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
UNKNOWN_OPCODE = 0x90          # 0x80-0xFF: reserved for private records; readers skip them


def _messages(dive_cache, profile):
    from auvdiag_cli.simulator.writers.ros import RosMessages, ros_topics

    messages = RosMessages(False, ros_topics(profile))
    records = list(messages.serialised(dive_cache("paper-flow-sensor-covered", 31), profile))
    return messages, records


def _write(path, dive_cache, profile, *, order="time", channels_per_topic=1, **options):
    from mcap.writer import Writer

    messages, records = _messages(dive_cache, profile)
    if order == "reversed-halves":        # the second half of the dive in the first chunks
        half = len(records) // 2
        records = records[half:] + records[:half]
    with path.open("wb") as stream:
        writer = Writer(stream, **options)
        writer.start(profile="ros2", library="layout test")
        channels = {}
        for topic, msgtype in messages.topics.items():
            text, _ = messages.store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(msgtype, "ros2msg", text.encode())
            channels[topic] = [writer.register_channel(topic, "cdr", schema)
                               for _ in range(channels_per_topic)]
        for index, (time_ns, topic, data) in enumerate(records):
            channel = channels[topic][index % channels_per_topic]
            writer.add_message(channel, log_time=time_ns, data=data, publish_time=time_ns)
        writer.finish()
    return path


def _with_unknown_records(path):
    """Private records (unknown opcodes) after the header and before the data end; the
    file has no summary, so no offset needs moving."""
    data = path.read_bytes()
    record = bytes([UNKNOWN_OPCODE]) + struct.pack("<Q", 11) + b"private rec"
    header_end = 8 + 1 + 8 + struct.unpack_from("<Q", data, 9)[0]
    data_end = data.rindex(b"\x0f" + struct.pack("<Q", 4))   # DataEnd: opcode 0x0F, length 4
    path.write_bytes(data[:header_end] + record + data[header_end:data_end] + record * 3
                     + data[data_end:])
    return path


def _diagnosis(log):
    _, report = diagnose_json(log)
    return {key: report[key] for key in ("verdict", "component", "case", "b", "onset_s",
                                         "detected_at_s", "duration_s")} | {
        "max_g": [s["max_g"] for s in report["segments"]],
        "completeness": report["completeness"]["status"]}


NO_SUMMARY = {"use_statistics": False, "use_summary_offsets": False, "repeat_channels": False,
              "repeat_schemas": False}


@pytest.fixture(scope="module")
def canonical(tmp_path_factory, dive_cache, profile):
    path = _write(tmp_path_factory.mktemp("mcap") / "canonical.mcap", dive_cache, profile)
    return _diagnosis(path)


def _layouts():
    from mcap.writer import CompressionType, IndexType

    return {
        "summary-without-channels": {"repeat_channels": False, "repeat_schemas": False},
        "summary-without-schemas": {"repeat_schemas": False},
        "no-summary": {**NO_SUMMARY, "index_types": IndexType.NONE},
        "no-chunk-indexes": {"index_types": IndexType.NONE},
        "no-message-indexes": {"index_types": IndexType.CHUNK},
        "no-statistics": {"use_statistics": False},
        "not-chunked": {"use_chunking": False},
        "uncompressed-chunks": {"compression": CompressionType.NONE},
        "lz4-chunks": {"compression": CompressionType.LZ4},
        "chunks-out-of-time-order": {"order": "reversed-halves", "chunk_size": 16_384},
        "two-channels-per-topic": {"channels_per_topic": 2, "chunk_size": 16_384},
    }


@pytest.mark.parametrize("layout", list(_layouts()))
def test_every_layout_gives_the_canonical_diagnosis(tmp_path, dive_cache, profile, canonical,
                                                     layout):
    path = _write(tmp_path / f"{layout}.mcap", dive_cache, profile, **_layouts()[layout])
    assert canonical["verdict"] == "fault" and canonical["component"] == "flow_sensor"
    assert _diagnosis(path) == canonical


def test_unknown_opcodes_are_skipped(tmp_path, dive_cache, profile, canonical):
    from mcap.writer import IndexType

    path = _write(tmp_path / "private.mcap", dive_cache, profile, **NO_SUMMARY,
                  index_types=IndexType.NONE)
    assert bytes([UNKNOWN_OPCODE]) + struct.pack("<Q", 11) not in path.read_bytes()
    _with_unknown_records(path)
    assert path.read_bytes().count(b"private rec") == 4
    assert _diagnosis(path) == canonical


def test_summary_without_channels_is_inspected(tmp_path, dive_cache, profile):
    path = _write(tmp_path / "bare-summary.mcap", dive_cache, profile,
                  repeat_channels=False, repeat_schemas=False)
    result = runner.invoke(app, ["inspect", str(path)])
    assert result.exit_code == 0, result.output
    assert "/imu/data" in result.stdout and "MISSING" not in result.stdout


def _read_signals(path, profile):
    from adapters.mcap import McapAdapter

    return McapAdapter().read(path, profile.sources["ros"], "mcap")


def test_wanted_messages_are_found_through_the_message_indexes(tmp_path, dive_cache, profile,
                                                               monkeypatch):
    """With message indexes no chunk is walked record by record."""
    import adapters.mcap

    path = _write(tmp_path / "indexed.mcap", dive_cache, profile, chunk_size=16_384)
    walked = _read_signals(path, profile)

    def never(*_):
        raise AssertionError("a chunk was walked record by record")

    monkeypatch.setattr(adapters.mcap, "records_in", never)
    indexed = _read_signals(path, profile)
    assert walked.series.keys() == indexed.series.keys() and indexed.messages_read > 1000
    for name, series in walked.series.items():
        assert series.equals(indexed.series[name])


def test_a_message_index_that_does_not_match_its_chunk_is_not_followed(
        tmp_path, dive_cache, profile, canonical, monkeypatch):
    """An index entry pointing one byte off its message: that chunk is walked instead."""
    from mcap.reader import SeekingReader

    import adapters.mcap

    path = _write(tmp_path / "bad-index.mcap", dive_cache, profile, chunk_size=16_384)
    with path.open("rb") as stream:
        chunk_index = SeekingReader(stream).get_summary().chunk_indexes[3]
    data = bytearray(path.read_bytes())
    at = min(chunk_index.message_index_offsets.values()) + 1 + 8 + 2 + 4 + 8  # 1st offset
    data[at:at + 8] = struct.pack("<Q", struct.unpack_from("<Q", data, at)[0] + 1)
    path.write_bytes(bytes(data))
    walks = []
    records_in = adapters.mcap.records_in
    monkeypatch.setattr(adapters.mcap, "records_in",
                        lambda *a: walks.append(a) or records_in(*a))
    assert _diagnosis(path) == canonical and len(walks) == 1


def test_indexes_that_leave_out_messages_the_statistics_count_are_not_trusted(
        tmp_path, dive_cache, profile, monkeypatch):
    """A chunk whose message indexes list only some of its channels: the messages counted
    in the statistics and not found make the reader go front to back instead."""
    import adapters.mcap

    path = _write(tmp_path / "short-index.mcap", dive_cache, profile, chunk_size=16_384)
    whole = _read_signals(path, profile)
    read_index_entries = adapters.mcap.read_index_entries

    def one_channel_short(stream, chunk_index, channels):
        entries = read_index_entries(stream, chunk_index, channels)
        return dict(list(entries.items())[1:]) if chunk_index.chunk_start_offset > 10_000 \
            else entries

    monkeypatch.setattr(adapters.mcap, "read_index_entries", one_channel_short)
    short = _read_signals(path, profile)
    for name, series in whole.series.items():
        assert series.equals(short.series[name])
