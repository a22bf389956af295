"""MCAP records front to back, with every size a file states checked before it is trusted,
and each wanted channel's messages routed to the collector.

The walk needs nothing from the summary section (the specification makes it optional, and
lets a writer leave Channel and Schema records out of it); unknown opcodes are skipped.
Chunks are decompressed here, never beyond the size they declare, and a declared size is
itself capped: a flipped length byte costs a chunk, not the machine's memory."""

import contextlib
import io
from collections.abc import Callable, Iterator, Sequence
from typing import Any, BinaryIO

import numpy as np

from adapters.collect import SignalCollector
from adapters.limits import MAX_CHUNK_BYTES
from adapters.mcap_index import LocatedMessages, chunk_data
from adapters.protobuf_schema import SchemaError
from adapters.ros_columns import TopicBatches
from auvdiag_errors import LogError

_READ_STEP = 1 << 20


class ChunkDamaged(ValueError):
    """A chunk's declared size or compression cannot be right."""


def decoder_factories() -> list[Any]:
    from mcap.decoder import DecoderFactory
    from mcap_ros1.decoder import DecoderFactory as Ros1DecoderFactory
    from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory

    class JsonDecoderFactory(DecoderFactory):
        def decoder_for(self, message_encoding: str, schema: Any
                        ) -> Callable[[bytes], Any] | None:
            import json

            return json.loads if message_encoding == "json" else None

    return [Ros2DecoderFactory(), Ros1DecoderFactory(), JsonDecoderFactory()]


def protobuf_decoder(channel: Any, schema: Any, paths: Sequence[str]
                     ) -> Callable[[bytes], Any] | None:
    """A Protocol Buffers channel's decoder of the fields on ``paths`` (None: the channel
    is not Protocol Buffers; SchemaError: its schema says nothing of them)."""
    if channel.message_encoding != "protobuf":
        return None
    if schema is None or schema.encoding != "protobuf":
        raise SchemaError("its Protocol Buffers messages come without their FileDescriptorSet "
                          "(a schema of encoding 'protobuf'), which says what they hold")
    from adapters.protobuf_decode import decoder
    from adapters.protobuf_schema import message_types

    return decoder(message_types(schema.data), schema.name, paths)


def decompressed(chunk: Any) -> bytes:
    """The chunk's records, at most ``uncompressed_size`` bytes of them."""
    size = chunk.uncompressed_size
    if size > MAX_CHUNK_BYTES:
        raise ChunkDamaged(f"a chunk declares {size} bytes uncompressed")
    if chunk.compression == "":
        return bytes(chunk.data)
    if chunk.compression == "zstd":
        import zstandard

        parts, total = [], 0
        with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(chunk.data)) as reader:
            while total < size:
                part = reader.read(min(_READ_STEP, size - total))
                if not part:
                    break
                parts.append(part)
                total += len(part)
        return b"".join(parts)
    if chunk.compression == "lz4":
        import lz4.frame

        return bytes(lz4.frame.LZ4FrameDecompressor().decompress(chunk.data, max_length=size))
    raise ChunkDamaged(f"unknown chunk compression {chunk.compression[:20]!r}")


def chunk_records(chunk: Any) -> Iterator[Any]:
    """The records inside a chunk (its CRC checked when it has one)."""
    yield from records_in(chunk, chunk_data(chunk, decompressed(chunk)))


def records_in(chunk: Any, data: np.ndarray) -> Iterator[Any]:
    """The records of a chunk whose uncompressed ``data`` is already checked."""
    from dataclasses import replace

    from mcap.stream_reader import breakup_chunk

    plain = replace(chunk, compression="", data=data.tobytes(), uncompressed_size=data.size,
                    uncompressed_crc=0)
    yield from breakup_chunk(plain)


def schema_fields(schemas: dict[int, Any]) -> dict[int, tuple[str, ...]]:
    """Field paths of each ros2msg, JSON Schema or protobuf schema (others list none)."""
    import json

    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from adapters.fieldnames import json_schema_paths, ros_field_paths
    from adapters.protobuf_decode import field_paths
    from adapters.protobuf_schema import message_types

    store, fields = get_typestore(Stores.EMPTY), {}
    for schema_id, schema in schemas.items():
        try:
            if schema.encoding == "ros2msg":
                store.register(get_types_from_msg(schema.data.decode(), schema.name))
                fields[schema_id] = tuple(ros_field_paths(store, schema.name))
            elif schema.encoding == "jsonschema":
                fields[schema_id] = tuple(json_schema_paths(json.loads(schema.data)))
            elif schema.encoding == "protobuf":
                fields[schema_id] = tuple(field_paths(message_types(schema.data), schema.name))
        except Exception:  # a definition that cannot be parsed lists no fields
            continue
    return fields


# How many records a walk for JSON channels' first messages reads at most (the first
# chunk usually holds every channel's first message).
JSON_SAMPLE_RECORDS = 10_000


def json_message_fields(message: bytes) -> tuple[str, ...]:
    """The field paths of one JSON message (none where it is not a JSON object)."""
    import json

    from adapters.fieldnames import object_field_paths

    try:
        decoded = json.loads(message)
    except (ValueError, RecursionError):   # not JSON, or nested past Python's stack
        return ()
    return tuple(object_field_paths(decoded)) if isinstance(decoded, dict) else ()


def sampled_json_fields(stream: BinaryIO, size: int, channels: set[int]
                        ) -> dict[int, tuple[str, ...]]:
    """Field paths of JSON ``channels`` whose schema lists none, from the first message of
    each that the first JSON_SAMPLE_RECORDS records of the file hold."""
    from mcap.records import Message

    found: dict[int, tuple[str, ...]] = {}
    stream.seek(0)
    with contextlib.suppress(Exception):     # a damaged file lists what it could
        for count, record in enumerate(walk_records(stream, size, Progress())):
            if count >= JSON_SAMPLE_RECORDS or not channels - found.keys():
                break
            if isinstance(record, Message) and record.channel_id in channels \
                    and record.channel_id not in found:
                found[record.channel_id] = json_message_fields(record.data)
    return found


class Progress:
    """How far a walk got (the byte after the last whole record), and the chunks it had to
    leave out because their contents were damaged while the file's framing held."""

    def __init__(self) -> None:
        self.good_bytes = 0
        self.skipped: list[tuple[int, str]] = []     # (chunk offset, why)


def walk_records(stream: BinaryIO, size: int, progress: Progress) -> Iterator[Any]:
    """Every record of the file in file order, chunks opened in place; a chunk whose
    contents cannot be read is skipped (and noted in ``progress``), the walk goes on."""
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader

    reader = StreamReader(stream, emit_chunks=True, record_size_limit=size)
    progress.good_bytes = stream.tell()
    for record in reader.records:
        if isinstance(record, Chunk):
            try:
                inner = list(chunk_records(record))
            except Exception as error:  # zstd, lz4, CRC or record errors inside the chunk
                progress.skipped.append((progress.good_bytes,
                                         str(error).strip() or type(error).__name__))
                inner = []
            yield from inner
        else:
            yield record
        progress.good_bytes = stream.tell()


class ChannelRouter:
    """Sends each message of a wanted topic to the collector: CDR messages whose schema
    rosbags can parse are batched for the column walker; any other channel is decoded one
    message at a time by the mcap decoder for its encoding."""

    def __init__(self, collector: SignalCollector) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.collector = collector
        self.schemas: dict[int, Any] = {}
        self.topics: dict[str, str] = {}                 # every topic seen → schema name
        self.routes: dict[int, tuple[str, Callable[[bytes], Any] | None]] = {}
        self.msgtypes: dict[str, str] = {}               # batched topic → message type
        self.store = get_typestore(Stores.EMPTY)
        self.batches = TopicBatches(collector, self.msgtypes, True, self.store,
                                    self.store.deserialize_cdr)
        self.factories: list[Any] | None = None       # made when a channel is not batched
        self.counts: dict[int, int] = {}                 # wanted channel → messages taken

    def take(self, record: Any) -> None:
        from mcap.records import Channel, Message, Schema

        if isinstance(record, Message):
            self.message(record.channel_id, record.log_time, record.data)
        elif isinstance(record, Schema):
            self.schemas[record.id] = record
        elif isinstance(record, Channel):
            self.channel(record)

    def channel(self, channel: Any) -> None:
        schema = self.schemas.get(channel.schema_id)
        self.topics[channel.topic] = schema.name if schema is not None else ""
        if self.collector.wants(channel.topic) and channel.id not in self.routes:
            self.routes[channel.id] = (channel.topic, self._decoder(channel, schema))

    def message(self, channel_id: int, time_ns: int, data: bytes) -> None:
        route = self.routes.get(channel_id)
        if route is None:
            return
        topic, decode = route
        self.counts[channel_id] = self.counts.get(channel_id, 0) + 1
        if decode is None:
            self.batches.append(topic, time_ns, data)
        else:
            self.collector.add(topic, time_ns, decode(data))

    def take_located(self, data: np.ndarray, located: dict[int, LocatedMessages]) -> None:
        """A chunk's wanted messages, found through its message indexes."""
        for channel_id, found in located.items():
            topic, decode = self.routes[channel_id]
            self.counts[channel_id] = self.counts.get(channel_id, 0) + found.times_ns.size
            if decode is None:
                self.batches.extend(topic, found.times_ns, data, found.starts, found.ends)
                continue
            for time_ns, start, end in zip(found.times_ns.tolist(), found.starts.tolist(),
                                           found.ends.tolist(), strict=True):
                self.collector.add(topic, time_ns, decode(data[start:end].tobytes()))

    def flush(self) -> None:
        self.batches.flush()

    def _decoder(self, channel: Any, schema: Any) -> Callable[[bytes], Any] | None:
        """None: batch it (CDR with a ros2msg schema of one type per topic)."""
        if (channel.message_encoding == "cdr" and schema is not None
                and schema.encoding == "ros2msg"
                and self.msgtypes.get(channel.topic, schema.name) == schema.name
                and self._register(schema)):
            self.msgtypes[channel.topic] = schema.name
            return None
        try:
            decoder = protobuf_decoder(channel, schema, self.collector.field_paths(
                channel.topic))
        except SchemaError as error:
            raise LogError(self.collector.path, f"cannot decode {channel.topic}: "
                                                f"{error}") from None
        if decoder is not None:
            return decoder
        if self.factories is None:
            self.factories = decoder_factories()
        for factory in self.factories:
            # The vendored ROS 2 definition parser prints to stderr about a schema it cannot
            # parse, and then raises: the exception is what we report.
            with contextlib.redirect_stderr(io.StringIO()):
                decoder = factory.decoder_for(channel.message_encoding, schema)
            if decoder is not None:
                return decoder
        raise LogError(self.collector.path, f"cannot decode {channel.topic}: no decoder for "
                                            f"message encoding {channel.message_encoding!r}")

    def _register(self, schema: Any) -> bool:
        from rosbags.typesys import get_types_from_msg

        try:
            self.store.register(get_types_from_msg(schema.data.decode(), schema.name))
        except Exception:  # a definition rosbags cannot parse: the generic decoder will do
            return False
        return True
