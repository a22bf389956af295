"""Standalone MCAP files through the `mcap` library, with ros2 (CDR), ros1 and JSON
message encodings. Only the profile's channels are decoded; the summary (when present) lists
channels and the log's time span without scanning, and a damaged file is read up to the
damage."""

import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO

from adapters.collect import SignalCollector
from adapters.errors import LogError
from adapters.inventory import LogInventory, TopicInfo
from adapters.ros_columns import TopicBatches
from adapters.signals import LogSources, Signals

MCAP_MAGIC = b"\x89MCAP0\r\n"


def _decoder_factories() -> list[Any]:
    from mcap.decoder import DecoderFactory
    from mcap_ros1.decoder import DecoderFactory as Ros1DecoderFactory
    from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory

    class JsonDecoderFactory(DecoderFactory):
        def decoder_for(self, message_encoding: str, schema: Any
                        ) -> Callable[[bytes], Any] | None:
            return json.loads if message_encoding == "json" else None

    return [Ros2DecoderFactory(), Ros1DecoderFactory(), JsonDecoderFactory()]


def salvage_mcap(path: Path, collector: SignalCollector, fmt: str, reason: str) -> Signals:
    """Read an MCAP front to back without its index, up to the first damaged record."""
    from mcap.reader import NonSeekingReader

    topics: dict[str, str] = {}
    try:
        with path.open("rb") as stream:
            reader = NonSeekingReader(stream, decoder_factories=_decoder_factories())
            # log_time_order=False: sorting would buffer everything and yield nothing on damage.
            for schema, channel, message, decoded in reader.iter_decoded_messages(
                    topics=sorted(collector.topics), log_time_order=False):
                topics[channel.topic] = schema.name if schema else ""
                collector.add(channel.topic, message.log_time, decoded)
    except LogError:
        raise
    except Exception as error:  # truncation surfaces as EndOfFile, struct.error, zstd errors
        if collector.count == 0:
            raise LogError(path, "damaged MCAP, nothing readable "
                                 f"({reason}; {str(error) or type(error).__name__})") from None
        collector.notes.append(
            f"log damaged ({reason}); read {collector.count} messages up to the damage and "
            "analysed that part")
    else:
        collector.notes.append(f"index unusable ({reason}); read the file sequentially")
    missing = collector.missing_topics(set(topics))
    if missing:
        raise LogError(path, f"missing topic(s) {', '.join(missing)} in the readable part")
    return collector.finish(fmt, None, None, topics)


def _cdr_typestore(summary: Any, topics: list[str]) -> Any | None:
    """The fast path for ROS 2 channels: a rosbags type store of the file's own message
    definitions, for column-wise reading (`adapters.ros_columns`) and rosbags' generated
    CDR deserialisers. None when a wanted channel is not CDR with a ros2msg schema."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    for channel in summary.channels.values():
        if channel.topic not in topics:
            continue
        schema = summary.schemas.get(channel.schema_id)
        if (channel.message_encoding != "cdr" or schema is None
                or schema.encoding != "ros2msg"):
            return None
        try:
            store.register(get_types_from_msg(schema.data.decode(), schema.name))
        except Exception:  # a definition rosbags cannot parse: the generic decoder will do
            return None
    return store


def _file_order(reader: Any, stream: BinaryIO, summary: Any, topics: list[str]
                ) -> Iterator[tuple[Any, Any]]:
    """(channel, message) of ``topics`` in file order, one chunk in memory at a time. The
    library's own file-order iteration queues every chunk's messages behind the remaining
    chunks, so it holds the whole file's messages before yielding the last chunk's."""
    from mcap.data_stream import ReadDataStream
    from mcap.records import Chunk, Message
    from mcap.stream_reader import breakup_chunk

    if not summary.chunk_indexes:
        for _, channel, message in reader.iter_messages(topics=topics, log_time_order=False):
            yield channel, message
        return
    wanted = {c.id: c for c in summary.channels.values() if c.topic in topics}
    for index in sorted(summary.chunk_indexes, key=lambda i: i.chunk_start_offset):
        if index.message_index_offsets and wanted.keys().isdisjoint(
                index.message_index_offsets):
            continue                                  # no wanted channel in this chunk
        stream.seek(index.chunk_start_offset + 1 + 8)  # opcode and record length
        chunk = Chunk.read(ReadDataStream(stream))
        for record in breakup_chunk(chunk, validate_crc=True):
            if isinstance(record, Message) and record.channel_id in wanted:
                yield wanted[record.channel_id], record


class McapAdapter:
    """A standalone .mcap file (any profile: ros2, ros1 or JSON-encoded channels)."""

    family = "ros"
    formats = ("mcap",)

    def sniff(self, path: Path) -> str | None:
        if not path.is_file():
            return None
        with path.open("rb") as stream:
            return "mcap" if stream.read(len(MCAP_MAGIC)) == MCAP_MAGIC else None

    def read(self, path: Path, sources: LogSources) -> Signals:
        from mcap.reader import SeekingReader

        collector = SignalCollector(path, sources)
        with path.open("rb") as stream:
            try:
                reader = SeekingReader(stream, decoder_factories=_decoder_factories())
                summary = reader.get_summary()
            except Exception as error:  # no valid footer/summary: a truncated recording
                return salvage_mcap(path, collector, "mcap", str(error))
            if summary is None:
                return salvage_mcap(path, collector, "mcap", "the file has no summary")
            return self._read_indexed(reader, summary, stream, collector)

    def _read_indexed(self, reader: Any, summary: Any, stream: BinaryIO,
                      collector: SignalCollector) -> Signals:
        topics = {c.topic: _schema_name(summary.schemas, c.schema_id)
                  for c in summary.channels.values()}
        missing = collector.missing_topics(set(topics))
        if missing:
            raise LogError(collector.path, f"missing topic(s) {', '.join(missing)}")
        wanted = sorted(collector.topics & set(topics))
        try:
            store = _cdr_typestore(summary, wanted)
            if store is None:
                for _, channel, message, decoded in reader.iter_decoded_messages(topics=wanted):
                    collector.add(channel.topic, message.log_time, decoded)
            else:
                # File order, not a merge by log time (the merge costs more than decoding);
                # resampling sorts a series if its messages were stored out of order.
                batches = TopicBatches(collector, topics, True, store, store.deserialize_cdr)
                for channel, message in _file_order(reader, stream, summary, wanted):
                    batches.append(channel.topic, message.log_time, message.data)
                batches.flush()
        except LogError:
            raise
        except Exception as error:  # a damaged chunk: keep what came before it
            fresh = SignalCollector(collector.path, collector.sources)
            return salvage_mcap(collector.path, fresh, "mcap", str(error))
        stats = summary.statistics
        return collector.finish("mcap", stats.message_start_time if stats else None,
                                stats.message_end_time if stats else None, topics)

    def inventory(self, path: Path) -> LogInventory:
        """From the summary when there is one, else by a raw scan (nothing decoded)."""
        from mcap.reader import NonSeekingReader, SeekingReader

        with path.open("rb") as stream:
            try:
                summary = SeekingReader(stream).get_summary()
            except Exception:  # no usable footer: fall through to the scan
                summary = None
            if summary is not None and summary.statistics is not None:
                stats = summary.statistics
                topics = [TopicInfo(c.topic, _schema_name(summary.schemas, c.schema_id),
                                    stats.channel_message_counts.get(c.id, 0))
                          for c in summary.channels.values()]
                return LogInventory("mcap", stats.message_start_time, stats.message_end_time,
                                    sorted(topics, key=lambda t: t.name))
            stream.seek(0)
            counts: dict[tuple[str, str], int] = {}
            first = last = None
            notes: list[str] = []
            try:
                for schema, channel, message in NonSeekingReader(stream).iter_messages(
                        log_time_order=False):
                    key = (channel.topic, schema.name if schema else "")
                    counts[key] = counts.get(key, 0) + 1
                    first = message.log_time if first is None else min(first, message.log_time)
                    last = message.log_time if last is None else max(last, message.log_time)
            except Exception as error:  # truncated: report what was readable
                notes.append(f"damaged after {sum(counts.values())} messages: "
                             f"{str(error) or type(error).__name__}")
            topics = [TopicInfo(t, n, c) for (t, n), c in sorted(counts.items())]
            return LogInventory("mcap", first, last, topics, notes)


def _schema_name(schemas: dict[int, Any], schema_id: int) -> str:
    schema = schemas.get(schema_id)
    return schema.name if schema is not None else ""
