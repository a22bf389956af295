"""The rows of one table read straight from an SQLite file's b-tree pages with NumPy, a
few thousand pages at a time: where each row's values lie in the pages' bytes, with no
Python object per row. (sqlite3 hands every blob over as a bytes object of its own, which
was most of the time a ROS 2 bag took to read.)

Only what a finished file holds is followed: a rowid table, its pages inside the file, no
write-ahead log or hot journal beside it, every structure where the format puts it.
Anything else raises `NotPlain`, and the caller reads through sqlite, which handles every
case (and all damage) this reader does not. The layout is sqlite.org/fileformat2.html."""

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adapters.packed import gather_words
from adapters.recognise import SQLITE_MAGIC

INTERIOR_TABLE, LEAF_TABLE = 0x05, 0x0D
INTERIOR_HEADER, LEAF_HEADER = 12, 8
MAX_DEPTH = 24                 # far more levels than 2**63 rows need at the smallest page
BYTES_AT_ONCE = 4 << 20        # of pages read and decoded together: bounds memory
READ_ACROSS_BYTES = 32 << 10   # pages this close come in one read, with those between
# Bytes a value of serial type 0 to 11 takes (10 and 11 are reserved: never written).
SERIAL_SIZES = np.array([0, 1, 2, 3, 4, 6, 8, 8, 0, 0, -1, -1], np.int64)
INTEGER_TYPES = (1, 2, 3, 4, 5, 6, 8, 9)
LARGEST_SERIAL = 1 << 40       # beyond any value a page holds; keeps arithmetic in int64


class NotPlain(ValueError):
    """The file holds something this reader does not follow: read it through sqlite."""


@dataclass(frozen=True)
class Records:
    """Consecutive rows of a table, in rowid order, located in the bytes of their pages."""

    data: np.ndarray            # the pages the rows lie in (uint8)
    rowids: np.ndarray          # int64, increasing
    serial_types: np.ndarray    # (rows, columns): how each value is stored
    starts: np.ndarray          # (rows, columns): where each value begins in ``data``
    sizes: np.ndarray           # (rows, columns): its length in bytes
    local_ends: np.ndarray      # where each row's bytes on its leaf page end

    def integers(self, column: int) -> np.ndarray:
        """The column's integer values (big-endian, two's complement, 0 to 8 bytes)."""
        types = self.serial_types[:, column]
        if not np.isin(types, INTEGER_TYPES).all():
            raise NotPlain("a value that is not an integer")
        widths = self.sizes[:, column]
        if (self.starts[:, column] + widths > self.local_ends).any():
            raise NotPlain("an integer outside its record")
        values = _big_endian(self.data, self.starts[:, column], widths)
        values[types == 9] = 1                               # types 8 and 9: 0 and 1
        return values

    def blobs(self, column: int, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the blobs of ``rows`` begin and end in ``data`` (each wholly on its page:
        one continuing on overflow pages is not followed here)."""
        types = self.serial_types[rows, column]
        if ((types < 12) | (types % 2 == 1)).any():
            raise NotPlain("a value that is not a blob")
        starts = self.starts[rows, column]
        ends = starts + self.sizes[rows, column]
        if (ends > self.local_ends[rows]).any():
            raise NotPlain("a blob continues on overflow pages")
        return starts, ends


class SqliteFile:
    """One SQLite database file, its pages read on demand."""

    def __init__(self, path: Path) -> None:
        for journal in (f"{path}-wal", f"{path}-journal"):
            if os.path.exists(journal) and os.path.getsize(journal) > 0:
                raise NotPlain("changes not yet written back to the file")
        self.path = path
        # One buffer for every read: fresh pages from the system cost more than reading
        # into them (their first touch faults), so each `Records` lives until the next.
        self.buffer = np.empty(0, np.uint8)
        self.file = open(path, "rb")     # noqa: SIM115 - closed by `close`
        header = self.file.read(100)
        if len(header) < 100 or header[:16] != SQLITE_MAGIC:
            self.close()
            raise NotPlain("not an SQLite file")
        size = int.from_bytes(header[16:18], "big")
        self.page_size = 65536 if size == 1 else size
        self.usable = self.page_size - header[20]
        self.page_count = os.fstat(self.file.fileno()).st_size // max(self.page_size, 1)
        if (self.page_size < 512 or self.page_size & (self.page_size - 1)
                or self.usable < 480):
            self.close()
            raise NotPlain("an unusual page size")

    def close(self) -> None:
        self.file.close()

    def records(self, root: int, columns: int) -> Iterator[Records]:
        """The table's rows in rowid order, a few megabytes of leaf pages at a time. Each
        `Records` lies in the file's one buffer: use it before taking the next."""
        last_rowid = None
        for group in self._groups(self._leaf_pages(root)):
            data, bases = self._read_pages(group)
            records = _leaf_records(data, bases, self.usable, columns)
            rowids = records.rowids
            if rowids.size and ((np.diff(rowids) <= 0).any()
                                or (last_rowid is not None and rowids[0] <= last_rowid)):
                raise NotPlain("rows out of order")
            if rowids.size:
                last_rowid = int(rowids[-1])
            yield records

    def _groups(self, pages: np.ndarray) -> list[np.ndarray]:
        """``pages`` in groups of ``BYTES_AT_ONCE``."""
        size = max(1, BYTES_AT_ONCE // self.page_size)
        return [pages[first:first + size] for first in range(0, pages.size, size)]

    def _leaf_pages(self, root: int) -> np.ndarray:
        """The table's leaf pages in key order, walking its interior pages a level at a
        time (a page's children in cell order, then its right-most child). All leaves lie
        at one depth: the first page of a level says whether it is theirs (each leaf's own
        kind is checked as it is read)."""
        level, listed = np.array([root], np.int64), 0
        for _ in range(MAX_DEPTH):
            listed += level.size
            ordered = np.sort(level)
            if listed > self.page_count or (ordered[1:] == ordered[:-1]).any():
                raise NotPlain("a page listed twice")
            data, bases = self._read_pages(level[:1])
            if data[bases[0]] == LEAF_TABLE:
                return level
            level = np.concatenate([self._children(group) for group in self._groups(level)])
        raise NotPlain("a tree deeper than any table's")

    def _children(self, pages: np.ndarray) -> np.ndarray:
        """The pages that interior ``pages`` point to, in key order."""
        data, bases = self._read_pages(pages)
        if not (data[bases] == INTERIOR_TABLE).all():
            raise NotPlain("not a rowid table's interior page")
        cells, counts = _cell_offsets(data, bases, self.usable, INTERIOR_HEADER, 4)
        children = np.empty(cells.size + bases.size, np.int64)
        last = np.cumsum(counts + 1) - 1
        children[last] = _unsigned(data, bases + 8, 4)        # the right-most child
        children[np.setdiff1d(np.arange(children.size), last, assume_unique=True)] = \
            _unsigned(data, cells, 4)
        return children

    def _read_pages(self, numbers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pages in ``data``, and where each of ``numbers`` begins there. Pages close
        together come in one read with those between them (another table's pages lie
        between a table's as both grow: reading them is cheaper than a call each)."""
        if numbers.size and (numbers.min() < 2 or numbers.max() > self.page_count):
            raise NotPlain("a page outside the file")
        order = np.sort(numbers)
        breaks = np.flatnonzero(np.diff(order) * self.page_size > READ_ACROSS_BYTES)
        firsts, lasts = order[np.r_[0, breaks + 1]], order[np.r_[breaks, order.size - 1]]
        lengths = (lasts - firsts + 1) * self.page_size
        offsets = np.cumsum(lengths) - lengths
        if self.buffer.size < lengths.sum():
            self.buffer = np.empty(int(lengths.sum()), np.uint8)
        data = self.buffer[:int(lengths.sum())]
        for first, offset, length in zip(firsts.tolist(), offsets.tolist(), lengths.tolist(),
                                         strict=True):
            self.file.seek((first - 1) * self.page_size)
            if self.file.readinto(data[offset:offset + length].data) != length:
                raise NotPlain("the file ends inside a page")
        run = np.searchsorted(firsts, numbers, side="right") - 1
        return data, offsets[run] + (numbers - firsts[run]) * self.page_size


def _cell_offsets(data: np.ndarray, bases: np.ndarray, usable: int, header: int,
                  smallest_cell: int) -> tuple[np.ndarray, np.ndarray]:
    """Where each cell of the pages begins in ``data``, page by page, and each page's
    count of cells."""
    counts = _unsigned(data, bases + 3, 2)
    if (header + 2 * counts > usable).any():
        raise NotPlain("more cells than a page holds")
    pages = np.repeat(np.arange(bases.size), counts)
    within = np.arange(pages.size) - np.repeat(np.cumsum(counts) - counts, counts)
    pointers = np.repeat(bases + header, counts) + 2 * within
    offsets = _unsigned(data, pointers, 2)
    if ((offsets < header + 2 * counts[pages]) | (offsets + smallest_cell > usable)).any():
        raise NotPlain("a cell outside its page")
    return bases[pages] + offsets, counts


def _leaf_records(data: np.ndarray, bases: np.ndarray, usable: int, columns: int) -> Records:
    """The rows on leaf pages: each cell is the payload's size, the rowid, then the
    payload (the record), whose first part stays on the page when it is large."""
    if not (data[bases] == LEAF_TABLE).all():
        raise NotPlain("not a table's leaf page")
    cells, counts = _cell_offsets(data, bases, usable, LEAF_HEADER, 2)
    page_ends = np.repeat(bases, counts) + usable
    sizes, used = _varints(data, cells)
    rowids, more = _varints(data, cells + used)
    payloads = cells + used + more
    sizes = np.minimum(sizes, LARGEST_SERIAL).astype(np.int64)
    local_ends = payloads + _local_sizes(sizes, usable)
    pointer = np.where(local_ends - payloads < sizes, 4, 0)     # first overflow page
    if (local_ends + pointer > page_ends).any():
        raise NotPlain("a record runs off its page")
    header_sizes, used = _varints(data, payloads)
    at = payloads + used
    types = np.empty((cells.size, columns), np.int64)
    for column in range(columns):
        serial, used = _varints(data, at)
        types[:, column] = np.minimum(serial, LARGEST_SERIAL)
        at = at + used
    if (at != payloads + header_sizes.astype(np.int64)).any() or (at > local_ends).any():
        raise NotPlain("a record with other columns than the table's")
    value_sizes = _value_sizes(types)
    starts = at[:, None] + np.cumsum(value_sizes, axis=1) - value_sizes
    if (starts[:, -1] + value_sizes[:, -1] != payloads + sizes).any():
        raise NotPlain("a record whose values do not fill it")
    return Records(data, rowids.view(np.int64), types, starts, value_sizes, local_ends)


def _local_sizes(sizes: np.ndarray, usable: int) -> np.ndarray:
    """How much of each payload a table leaf keeps on the page (the format's rule)."""
    most = usable - 35
    least = (usable - 12) * 32 // 255 - 23
    spilled = least + (sizes - least) % (usable - 4)
    return np.where(sizes <= most, sizes, np.where(spilled <= most, spilled, least))


def _value_sizes(types: np.ndarray) -> np.ndarray:
    sizes = np.where(types >= 12, (types - 12) >> 1, SERIAL_SIZES.take(types, mode="clip"))
    if (sizes < 0).any():
        raise NotPlain("a reserved serial type")
    return sizes


def _varints(data: np.ndarray, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The variable-length integers at ``positions``: 7 bits a byte while the top bit is
    set, the ninth byte whole; their values (uint64) and lengths. Bytes past ``data``'s
    end read as the last byte: the callers' bounds checks then refuse the value."""
    first = data.take(positions, mode="clip")
    if (first < 0x80).all():                    # the usual case: small numbers, one byte
        return first.astype(np.uint64), np.ones(positions.size, np.int64)
    values = np.zeros(positions.size, np.uint64)
    lengths = np.zeros(positions.size, np.int64)
    going = np.ones(positions.size, bool)
    for index in range(9):
        byte = data.take(positions + index, mode="clip").astype(np.uint64)
        if index == 8:
            np.copyto(values, (values << np.uint64(8)) | byte, where=going)
            lengths[going] = 9
            break
        np.copyto(values, (values << np.uint64(7)) | (byte & np.uint64(0x7F)), where=going)
        ended = going & (byte < 0x80)
        lengths[ended] = index + 1
        going &= ~ended
        if not going.any():
            break
    return values, lengths


def _unsigned(data: np.ndarray, positions: np.ndarray, width: int) -> np.ndarray:
    """Unsigned big-endian integers of ``width`` (2 or 4) bytes: the pages' own fields.
    Each must lie inside ``data``."""
    return gather_words(data, positions, f">u{width}").astype(np.int64)


def _big_endian(data: np.ndarray, positions: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Big-endian two's complement integers of 0 to 8 bytes at ``positions``, each inside
    ``data`` (int64)."""
    if widths.size and (widths == widths[0]).all():           # the usual case: one width
        return _of_width(data, positions, int(widths[0]))
    values = np.zeros(positions.size, np.int64)
    for width in np.flatnonzero(np.bincount(widths)).tolist():      # widths are 0 to 8
        at = np.flatnonzero(widths == width)
        values[at] = _of_width(data, positions[at], width)
    return values


def _of_width(data: np.ndarray, positions: np.ndarray, width: int) -> np.ndarray:
    if width in (1, 2, 4, 8):
        return gather_words(data, positions, f">i{width}").astype(np.int64)
    value = np.zeros(positions.size, np.int64)
    for index in range(width):                            # 3 and 6 bytes: a byte at a time
        value = (value << 8) | data[positions + index]
    if width:
        value[value >= 1 << (8 * width - 1)] -= 1 << (8 * width)
    return value
