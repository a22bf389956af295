"""Which format a log is, from its content alone (and, for a ROS 2 bag, the metadata.yaml
beside its storage files), without importing any reader: a diagnosis then loads only the
reader of its own format."""

import re
import struct
from collections.abc import Callable
from pathlib import Path

from adapters.compressed import first_bytes, is_compressed

ROS1_MAGIC = b"#ROSBAG V2.0"
SQLITE_MAGIC = b"SQLite format 3\x00"
MCAP_MAGIC = b"\x89MCAP0\r\n"
ULOG_MAGIC = b"ULog\x01\x12\x35"
DATAFLASH_HEADER = b"\xa3\x95\x80"       # record header + FMT type
MAVLINK_MAGICS = (0xFE, 0xFD)            # MAVLink 1 and 2 frame start
PLAUSIBLE_EPOCH_US = (946_684_800_000_000, 4_102_444_800_000_000)   # years 2000 … 2100
CSV_DELIMITERS = (",", ";", "\t")
CSV_SNIFF_BYTES = 8192
# The clock column that names a per-topic CSV (one topic's messages, a row each): `%time`
# (ns since 1970) from `rostopic echo -p`; `Time` (s) from bag-to-CSV exports such as bagpy,
# taken only beside field-path columns (`header.seq`).
TOPIC_CSV_CLOCKS = {"%time": 1, "Time": 1_000_000_000}
TOPIC_CSV_FIELD_PREFIX = "field."
ALOG_LOGSTART = b"%% LOGSTART"          # MOOS pLogger's header line of the log's UNIX start


def _recording_order(path: Path) -> list[str | int]:
    """rosbag2 numbers split files ``NAME_0``, ``NAME_1``, … ``NAME_10``: numbers as numbers."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def _storage_kind(path: Path) -> str | None:
    """``.mcap`` or ``.db3`` for a storage file, also one rosbag2 compressed whole
    (compression mode ``file``: ``NAME_0.db3.zstd``)."""
    suffixes = path.suffixes[-2:]
    if suffixes[-1:] == [".zstd"]:
        suffixes = suffixes[:-1]
    kind = suffixes[-1] if suffixes else None
    return kind if kind in (".mcap", ".db3") else None


def _storage_files(directory: Path) -> list[Path]:
    return sorted((p for p in directory.iterdir() if _storage_kind(p)), key=_recording_order)


def bag_storages(path: Path) -> list[Path]:
    """A ROS 2 bag's storage files in recording order (a file given alone: itself)."""
    return _storage_files(path) if path.is_dir() else [path]


def bag_metadata(path: Path) -> Path:
    """Where a ROS 2 bag (its folder, or one storage file) keeps its metadata.yaml."""
    return (path if path.is_dir() else path.parent) / "metadata.yaml"


def csv_delimiter(line: str) -> str:
    return max(CSV_DELIMITERS, key=line.count)


def is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _head_lines(head: bytes) -> list[str] | None:
    if b"\0" in head:
        return None
    try:   # the read may end inside a line (or a character): keep whole lines only
        text = head.decode("utf-8") if len(head) < CSV_SNIFF_BYTES else head[
            :head.rfind(b"\n") + 1].decode("utf-8")
    except UnicodeDecodeError:
        return None
    return text.splitlines()


def topic_csv_clock(header: list[str]) -> str | None:
    """The clock column of a per-topic CSV's header (`TOPIC_CSV_CLOCKS`), or None."""
    if len(header) < 2 or header[0] not in TOPIC_CSV_CLOCKS:
        return None
    if header[0] == "%time" or any("." in name for name in header[1:]):
        return header[0]
    return None


def csv_header(line: str) -> list[str]:
    return [cell.strip() for cell in line.split(csv_delimiter(line))]


def first_line(path: Path) -> str:
    """The first line of a text file ('' for one that is not text or cannot be read)."""
    try:
        with path.open("rb") as stream:
            head = stream.readline(CSV_SNIFF_BYTES)
    except OSError:
        return ""
    try:
        return "" if b"\0" in head else head.decode("utf-8").rstrip("\r\n")
    except UnicodeDecodeError:
        return ""


def topic_csv_files(folder: Path) -> list[Path]:
    """The per-topic CSVs of a folder (its other files are not part of that log)."""
    return sorted(entry for entry in folder.iterdir()
                  if entry.suffix.lower() == ".csv" and entry.is_file()
                  and topic_csv_clock(csv_header(first_line(entry))) is not None)


def _ros2_bag_folder(path: Path) -> str | None:
    storage = _storage_files(path)
    if (path / "metadata.yaml").is_file() and storage:
        return "ros2-mcap" if _storage_kind(storage[0]) == ".mcap" else "db3"
    return None


def _ros_bag(path: Path, head: bytes) -> str | None:
    if head.startswith(ROS1_MAGIC):
        return "bag"
    if head.startswith(SQLITE_MAGIC):
        return "db3"
    if head.startswith(MCAP_MAGIC) and bag_metadata(path).is_file():
        return "ros2-mcap"
    return None


def _mcap(path: Path, head: bytes) -> str | None:
    return "mcap" if head.startswith(MCAP_MAGIC) else None


def _tlog(path: Path, head: bytes) -> str | None:
    if len(head) < 9 or head[8] not in MAVLINK_MAGICS:
        return None
    (time_us,) = struct.unpack(">Q", head[:8])
    return "tlog" if PLAUSIBLE_EPOCH_US[0] < time_us < PLAUSIBLE_EPOCH_US[1] else None


def _dataflash(path: Path, head: bytes) -> str | None:
    return "bin" if head.startswith(DATAFLASH_HEADER) else None


def _ulog(path: Path, head: bytes) -> str | None:
    return "ulog" if head.startswith(ULOG_MAGIC) else None


def _alog(path: Path, head: bytes) -> str | None:
    """A pLogger header (``%%`` lines, one of them LOGSTART) or, without one, lines of a
    time, a variable and a source."""
    if b"\0" in head:
        return None
    lines = head.splitlines()[:40]
    if any(line.startswith(ALOG_LOGSTART) for line in lines):
        return "alog"
    data = [line.split(None, 3) for line in lines if line.strip() and not line.startswith(b"%")]
    timed = len(data) >= 3 and all(
        len(parts) >= 3 and is_number(parts[0].decode("ascii", "replace"))
        and parts[1][:1].isalpha() for parts in data)
    return "alog" if timed else None


def _csv(path: Path, head: bytes) -> str | None:
    """Text whose first line names columns and whose next has as many cells, some numbers."""
    lines = _head_lines(head)
    if not lines or len(lines) < 2:
        return None
    delimiter = csv_delimiter(lines[0])
    header = [cell.strip() for cell in lines[0].split(delimiter)]
    row = [cell.strip() for cell in lines[1].split(delimiter)]
    named = len(header) >= 2 and all(header) and not any(map(is_number, header))
    if not (named and len(row) == len(header) and any(map(is_number, row))):
        return None
    return "topic-csv" if topic_csv_clock(header) is not None else "csv"


# Order matters: a ROS 2 bag's .mcap storage file is claimed as a bag before plain MCAP.
# CSV last: it is recognised by being text with a header, which the binary formats are not
# (nor a MOOS alog, whose lines are space-separated).
# Each is given the file and its first CSV_SNIFF_BYTES bytes.
_RECOGNISERS: tuple[tuple[tuple[str, ...], Callable[[Path, bytes], str | None]], ...] = (
    (("bag", "db3", "ros2-mcap"), _ros_bag), (("mcap",), _mcap), (("tlog",), _tlog),
    (("bin",), _dataflash), (("ulog",), _ulog), (("alog",), _alog),
    (("csv", "topic-csv"), _csv))
KNOWN_FORMATS = tuple(fmt for formats, _ in _RECOGNISERS for fmt in formats)
# Formats read gzip-compressed as well (`adapters.compressed`): the text logs read as streams.
COMPRESSED_FORMATS = ("alog", "csv")


def recognise(path: Path) -> str | None:
    """The format of the log at ``path`` (a file; a ROS 2 bag's folder; a folder of
    per-topic CSVs, or one such CSV alone); None if no format this tool reads."""
    if path.is_dir():
        return _ros2_bag_folder(path) or ("topic-csv" if topic_csv_files(path) else None)
    if not path.is_file():
        return None
    with path.open("rb") as stream:
        head = stream.read(CSV_SNIFF_BYTES)
    if is_compressed(head):           # only a text log is read compressed
        text = first_bytes(path, CSV_SNIFF_BYTES)
        fmt = _alog(path, text) or _csv(path, text)
        return fmt if fmt in COMPRESSED_FORMATS else None
    for _, recogniser in _RECOGNISERS:
        fmt = recogniser(path, head)
        if fmt is not None:
            return fmt
    return None
