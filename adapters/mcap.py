"""MCAP files, standalone or a ROS 2 bag's storage, through the `mcap` library, with ros2
(CDR), ros1 and JSON message encodings. Only the profile's channels are decoded. With a
complete summary the chunks holding wanted channels are read straight from their index; a
file without one (the specification makes summaries, indexes and statistics optional) or a
damaged file is read front to back, up to the damage."""

from pathlib import Path
from typing import Any, BinaryIO

from adapters.collect import SignalCollector
from adapters.inventory import LogInventory, TopicInfo, merged_inventory
from adapters.mcap_index import RECORD_HEAD, IndexUnusable, chunk_data, locate, read_index_entries
from adapters.mcap_records import (
    ChannelRouter,
    Progress,
    decompressed,
    json_message_fields,
    records_in,
    sampled_json_fields,
    schema_fields,
    walk_records,
)
from adapters.rosbag2 import Rosbag2Adapter
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

__all__ = ["McapAdapter", "Ros2McapAdapter", "read_mcap"]


def _problem(error: BaseException) -> str:
    return str(error).strip() or type(error).__name__


def _feed_sequential(storage: Path, collector: SignalCollector
                     ) -> tuple[dict[str, str], str | None]:
    """Walk an MCAP front to back without its summary, up to the first damaged record,
    noting what was lost: every topic seen → its schema name, and the first damage."""
    router = ChannelRouter(collector)
    progress = Progress()
    damage: str | None = None
    try:
        with storage.open("rb") as stream:
            for record in walk_records(stream, storage.stat().st_size, progress):
                router.take(record)
    except LogError:
        raise
    except Exception as error:  # truncation: EndOfFile, struct.error, CRC or zstd errors
        damage = _problem(error)
    try:
        router.flush()
    except LogError:
        raise
    except Exception as error:  # a message its own schema does not describe
        damage = damage or _problem(error)
    for at_byte, why in progress.skipped:
        reason = f"damaged chunk at byte {at_byte} left out ({why})"
        collector.notes.append(reason)
        collector.damaged(reason, at_byte)
    if damage is not None:
        reason = (f"log damaged at byte {progress.good_bytes} ({damage}); read "
                  f"{collector.count} messages up to the damage and analysed that part")
        collector.notes.append(reason)
        collector.damaged(reason, progress.good_bytes)
    return router.topics, damage or (progress.skipped[0][1] if progress.skipped else None)


def _summary(stream: BinaryIO, size: int) -> Any | None:
    """The summary section when it is there and whole enough to find every channel."""
    from mcap.reader import SeekingReader

    try:
        summary = SeekingReader(stream, record_size_limit=size).get_summary()
    except Exception:  # no valid footer or summary: a truncated or damaged recording
        return None
    if summary is None or not summary.channels:
        return None          # summaries need not repeat the Channel records
    in_chunks = {channel_id for index in summary.chunk_indexes
                 for channel_id in index.message_index_offsets}
    counted = set(summary.statistics.channel_message_counts) if summary.statistics else set()
    named = summary.channels.keys()
    schemas_known = all(c.schema_id == 0 or c.schema_id in summary.schemas
                        for c in summary.channels.values())
    if in_chunks - named or counted - named or not schemas_known:
        return None
    return summary


def summary_topics(storages: list[Path]) -> set[str] | None:
    """The topics of MCAP files from their summaries alone; None where one has none."""
    names: set[str] = set()
    for storage in storages:
        with storage.open("rb") as stream:
            summary = _summary(stream, storage.stat().st_size)
        if summary is None:
            return None
        names |= {channel.topic for channel in summary.channels.values()}
    return names


def _schema_name(schemas: dict[int, Any], schema_id: int) -> str:
    schema = schemas.get(schema_id)
    return schema.name if schema is not None else ""


class McapAdapter:
    """A standalone .mcap file (any profile: ros2, ros1 or JSON-encoded channels)."""

    family = "ros"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        return read_mcap([path], path, sources, fmt)

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        """From the summary when it has statistics, else by a raw scan (nothing decoded)."""
        with path.open("rb") as stream:
            summary = _summary(stream, path.stat().st_size)
            if summary is not None and summary.statistics is not None:
                stats = summary.statistics
                fields = schema_fields(summary.schemas)
                unlisted = {c.id for c in summary.channels.values()
                            if c.message_encoding == "json" and not fields.get(c.schema_id)}
                sampled = sampled_json_fields(stream, path.stat().st_size, unlisted) \
                    if unlisted else {}
                topics = [TopicInfo(c.topic, _schema_name(summary.schemas, c.schema_id),
                                    stats.channel_message_counts.get(c.id, 0),
                                    fields.get(c.schema_id) or sampled.get(c.id, ()))
                          for c in summary.channels.values()]
                return LogInventory("mcap", stats.message_start_time, stats.message_end_time,
                                    sorted(topics, key=lambda t: t.name))
            stream.seek(0)
            return _scanned_inventory(stream, path.stat().st_size)


class Ros2McapAdapter(Rosbag2Adapter):
    """A ROS 2 bag in MCAP storage: each storage file read as a standalone MCAP file is."""

    def read_storages(self, storages: list[Path], path: Path, sources: LogSources, fmt: str
                      ) -> Signals:
        return read_mcap(storages, path, sources, fmt)

    def storages_inventory(self, storages: list[Path], path: Path, fmt: str) -> LogInventory:
        return merged_inventory(fmt, [McapAdapter().inventory(storage, "mcap")
                                      for storage in storages])


def read_mcap(storages: list[Path], path: Path, sources: LogSources, fmt: str) -> Signals:
    """The profile's signals from the MCAP files ``storages`` of the log ``path`` (the file
    itself, or the storage files of a ROS 2 bag, in order): through the chunk indexes where
    the summary is whole, else, or when a chunk is damaged, front to back."""
    try:
        return _read_files(storages, SignalCollector(path, sources), fmt, indexed=True)
    except LogError:
        raise
    except Exception:  # a damaged chunk: read the files front to back instead
        return _read_files(storages, SignalCollector(path, sources), fmt, indexed=False)


def _read_files(storages: list[Path], collector: SignalCollector, fmt: str, indexed: bool
                ) -> Signals:
    topics: dict[str, str] = {}
    starts: list[int] = []
    ends: list[int] = []
    damage: str | None = None
    for storage in storages:
        with storage.open("rb") as stream:
            summary = _summary(stream, storage.stat().st_size) if indexed else None
            if summary is not None and summary.chunk_indexes:
                topics |= _read_indexed(summary, stream, collector)
                if summary.statistics is not None:
                    starts.append(summary.statistics.message_start_time)
                    ends.append(summary.statistics.message_end_time)
            else:
                seen, damaged = _feed_sequential(storage, collector)
                topics |= seen
                damage = damage or damaged
    if damage is not None and collector.count == 0:
        raise LogError(collector.path, f"damaged MCAP, nothing readable ({damage})")
    collector.require_topics(topics, " in the readable part" if damage is not None else "")
    return collector.finish(fmt, min(starts, default=None), max(ends, default=None), topics,
                            time_ordered=True)


def _read_indexed(summary: Any, stream: BinaryIO, collector: SignalCollector
                  ) -> dict[str, str]:
    router = ChannelRouter(collector)
    collector.resolve_topics(channel.topic for channel in summary.channels.values())
    for schema in summary.schemas.values():
        router.take(schema)
    for channel in summary.channels.values():
        router.take(channel)
    # File order, not a merge by log time (the merge costs more than decoding);
    # resampling sorts a series if its messages were stored out of order.
    _read_wanted_chunks(stream, summary, router)
    stats = summary.statistics
    if stats is not None and any(router.counts.get(c, 0) < stats.channel_message_counts.get(
            c, 0) for c in router.routes):
        raise IndexUnusable("the chunk indexes leave out messages the statistics count")
    router.flush()
    return router.topics


def _read_wanted_chunks(stream: BinaryIO, summary: Any, router: ChannelRouter) -> None:
    """Every chunk that may hold a wanted channel, in file order, one in memory at a time:
    its wanted messages found through its message indexes, or, where it has none that can
    be followed, by walking its records."""
    from mcap.data_stream import ReadDataStream
    from mcap.records import Chunk

    wanted = set(router.routes)
    for index in sorted(summary.chunk_indexes, key=lambda i: i.chunk_start_offset):
        if index.message_index_offsets and wanted.isdisjoint(index.message_index_offsets):
            continue                                  # no wanted channel in this chunk
        stream.seek(index.chunk_start_offset + RECORD_HEAD)
        chunk = Chunk.read(ReadDataStream(stream))
        data = chunk_data(chunk, decompressed(chunk))
        try:
            entries = read_index_entries(stream, index, wanted)
            located = {c: locate(data, c, found) for c, found in entries.items()}
        except IndexUnusable:
            located = None
        if located is None or not index.message_index_offsets:
            for record in records_in(chunk, data):
                router.take(record)
        else:
            router.take_located(data, located)


def _scanned_inventory(stream: BinaryIO, size: int) -> LogInventory:
    from mcap.records import Channel, Message, Schema

    schemas: dict[int, Any] = {}
    channels: dict[int, tuple[str, int]] = {}
    json_channels: set[int] = set()
    sampled: dict[tuple[str, int], tuple[str, ...]] = {}   # a JSON channel's first message
    counts: dict[int, int] = {}
    first = last = None
    notes: list[str] = []
    progress = Progress()
    try:
        for record in walk_records(stream, size, progress):
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = (record.topic, record.schema_id)
                if record.message_encoding == "json":
                    json_channels.add(record.id)
            elif isinstance(record, Message):
                counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
                key = channels.get(record.channel_id)
                if record.channel_id in json_channels and key and key not in sampled:
                    sampled[key] = json_message_fields(record.data)
                first = record.log_time if first is None else min(first, record.log_time)
                last = record.log_time if last is None else max(last, record.log_time)
    except Exception as error:  # truncated or damaged: report what was readable
        notes.append(f"damaged at byte {progress.good_bytes} after {sum(counts.values())} "
                     f"messages: {_problem(error)}")
    notes += [f"damaged chunk at byte {at} left out ({why})" for at, why in progress.skipped]
    totals: dict[tuple[str, int], int] = {}
    for channel_id, count in counts.items():
        key = channels.get(channel_id, (f"channel {channel_id}", -1))
        totals[key] = totals.get(key, 0) + count
    fields = schema_fields(schemas)
    topics = [TopicInfo(t, _schema_name(schemas, s), c,
                        fields.get(s) or sampled.get((t, s), ()))
              for (t, s), c in sorted(totals.items())]
    return LogInventory("mcap", first, last, topics, notes)
