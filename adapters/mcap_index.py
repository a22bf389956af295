"""A chunk's wanted messages found through its message indexes, all at once.

An indexed MCAP lists, after each chunk, one MessageIndex record per channel: the log time
and the offset in the uncompressed chunk of every message of that channel. Read with NumPy,
these locate every wanted message of a chunk in a few array operations, where walking the
chunk record by record costs microseconds a message in Python. An index is untrusted like
every other byte: each entry must point at a Message record of its channel with the time it
states, inside the chunk; one that does not makes the chunk `IndexUnusable`, and the caller
walks that chunk's records instead."""

import struct
import zlib
from dataclasses import dataclass
from typing import Any, BinaryIO

import numpy as np

from adapters.packed import gather_words

MESSAGE_OPCODE = 0x05
MESSAGE_INDEX_OPCODE = 0x07
RECORD_HEAD = 1 + 8            # opcode, record length
MESSAGE_HEAD = 2 + 4 + 8 + 8   # channel id, sequence, log time, publish time
INDEX_HEAD = 2 + 4             # channel id, byte length of the entries
INDEX_ENTRY = 8 + 8            # log time, offset


class IndexUnusable(ValueError):
    """A message index that cannot be followed; the chunk is walked instead."""


@dataclass(frozen=True)
class LocatedMessages:
    """One channel's messages in a chunk: the data of message i is
    ``records[starts[i]:ends[i]]``."""

    times_ns: np.ndarray     # int64
    starts: np.ndarray       # int64
    ends: np.ndarray         # int64


def chunk_data(chunk: Any, decompressed: bytes) -> np.ndarray:
    """The chunk's uncompressed records as bytes, its CRC checked when it states one."""
    if chunk.uncompressed_crc and zlib.crc32(decompressed) != chunk.uncompressed_crc:
        raise ValueError("chunk CRC mismatch")
    return np.frombuffer(decompressed, np.uint8)


def read_index_entries(stream: BinaryIO, chunk_index: Any, channels: set[int]
                       ) -> dict[int, np.ndarray]:
    """Per wanted channel in this chunk, its index entries as an (n, 2) array of
    (log time, offset)."""
    offsets = {c: o for c, o in chunk_index.message_index_offsets.items() if c in channels}
    if not offsets:
        return {}
    first = chunk_index.chunk_start_offset + chunk_index.chunk_length
    size = chunk_index.message_index_length
    if min(offsets.values()) < first or size <= 0:
        raise IndexUnusable("message index outside its chunk's index section")
    stream.seek(first)
    region = stream.read(size)
    entries = {}
    for channel, offset in offsets.items():
        at = offset - first
        if at + RECORD_HEAD + INDEX_HEAD > len(region) or region[at] != MESSAGE_INDEX_OPCODE:
            raise IndexUnusable(f"no message index for channel {channel} where stated")
        length, stated_channel, count = struct.unpack_from("<QHI", region, at + 1)
        start = at + RECORD_HEAD + INDEX_HEAD
        if (stated_channel != channel or count % INDEX_ENTRY or INDEX_HEAD + count > length
                or start + count > len(region)):
            raise IndexUnusable(f"message index of channel {channel} does not fit")
        entries[channel] = np.frombuffer(region, "<u8", count // 8, start).reshape(-1, 2)
    return entries


def locate(records: np.ndarray, channel: int, entries: np.ndarray) -> LocatedMessages:
    """Where each indexed message's data lies in the uncompressed chunk, every entry
    checked against the record it points at."""
    offsets = entries[:, 1]
    if (offsets > records.size - RECORD_HEAD - MESSAGE_HEAD).any():
        raise IndexUnusable("a message index points past its chunk")
    offsets = offsets.astype(np.int64)
    stated = gather_words(records, offsets + 1, "<u8")
    if (stated > np.uint64(records.size)).any():
        raise IndexUnusable("a message indexed runs past its chunk")
    lengths, head = stated.astype(np.int64), offsets + RECORD_HEAD
    if ((records[offsets] != MESSAGE_OPCODE).any() or (lengths < MESSAGE_HEAD).any()
            or (head + lengths > records.size).any()
            or (gather_words(records, head, "<u2") != channel).any()
            or (gather_words(records, head + 6, "<u8") != entries[:, 0]).any()):
        raise IndexUnusable("a message index entry does not match its message")
    order = np.argsort(offsets, kind="stable")
    return LocatedMessages(entries[order, 0].view(np.int64), (head + MESSAGE_HEAD)[order],
                           (head + lengths)[order])
