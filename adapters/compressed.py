"""Text logs kept gzip-compressed (a MOOS-IvP `.alog.gz` as pLogger's `CompressAlogs`
writes it, a `.csv.gz` from an archive): recognised by their content and read as they are,
streamed, never unpacked to disk. A stream cut short or damaged is read up to the damage."""

import gzip
import io
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

GZIP_MAGIC = b"\x1f\x8b"
# What reading a damaged stream raises: cut short (EOFError), a bad header or checksum
# (gzip.BadGzipFile, an OSError), bad deflate data (zlib.error).
DAMAGED_STREAM = (EOFError, OSError, zlib.error)
# A compressed stream is decompressed this much at a time: a read that meets the damage
# loses what it had decompressed, so only this much is lost before it.
_PIECE_BYTES = 1 << 16


def is_compressed(head: bytes) -> bool:
    return head.startswith(GZIP_MAGIC)


def open_binary(path: Path) -> io.BufferedReader | gzip.GzipFile:
    """The log's bytes, decompressed where it is gzip-compressed."""
    stream = path.open("rb")
    if not is_compressed(stream.read(len(GZIP_MAGIC))):
        stream.seek(0)
        return stream
    stream.close()
    return gzip.open(path, "rb")


def open_text(path: Path) -> TextIO:
    """The log as text (UTF-8, undecodable bytes replaced; newlines as written)."""
    return io.TextIOWrapper(open_binary(path), encoding="utf-8", errors="replace", newline="")


class Chunks:
    """A log's bytes in blocks of ``size`` (the last one shorter), decompressed where it is
    compressed; a compressed stream damaged part-way ends them there and ``stopped`` says
    why."""

    def __init__(self, path: Path, size: int) -> None:
        self.path, self.size = path, size
        self.stopped: str | None = None

    def __iter__(self) -> Iterator[bytes]:
        with open_binary(self.path) as stream:
            if not isinstance(stream, gzip.GzipFile):
                while block := stream.read(self.size):
                    yield block
                return
            pending = bytearray()
            try:
                while piece := stream.read1(_PIECE_BYTES):
                    pending += piece
                    if len(pending) >= self.size:
                        yield bytes(pending)
                        pending.clear()
            except DAMAGED_STREAM as error:
                self.stopped = damage(error)
            if pending:
                yield bytes(pending)


def first_bytes(path: Path, size: int) -> bytes:
    """Up to ``size`` bytes from the start of a log, decompressed where it is compressed:
    as many as its stream gives before any damage further on (which still shows what it
    is)."""
    with path.open("rb") as stream:
        raw = stream.read(_PIECE_BYTES)
        if not is_compressed(raw):
            return raw[:size] + (stream.read(size - len(raw)) if len(raw) < size else b"")
        decompressor = zlib.decompressobj(16 + zlib.MAX_WBITS)
        out = bytearray()
        while raw and len(out) < size and not decompressor.eof:
            try:
                out += decompressor.decompress(raw, size - len(out))
            except zlib.error:
                break
            raw = stream.read(_PIECE_BYTES)
    return bytes(out)


def damage(error: BaseException) -> str:
    """What a reading error of a compressed stream says about the file."""
    if isinstance(error, EOFError):
        return "the compressed log ends early (cut short?): read up to there"
    return f"the compressed log is damaged ({error}): read up to there"
