"""Log adapters: one per format, chosen by content, all producing `Signals`. A format's
reader is imported only when a log of that format is read."""

from collections.abc import Mapping
from dataclasses import replace
from functools import cache
from importlib import import_module
from pathlib import Path
from typing import Protocol, cast

from adapters.inventory import LogInventory, TopicInfo
from adapters.recognise import KNOWN_FORMATS, recognise
from adapters.ros_words import words_among
from adapters.signals import FieldSource, LogSources, SegmentMarker, SegmentSource, Signals
from auvdiag_errors import LogError

__all__ = [
    "FieldSource",
    "LogInventory",
    "LogSources",
    "SegmentMarker",
    "SegmentSource",
    "Signals",
    "TopicInfo",
    "detect_format",
    "inventory",
    "read_log",
    "with_ros_words",
]


class Adapter(Protocol):
    """One format's reader of the needed signals."""

    @property
    def family(self) -> str:
        """Which profile mapping it reads: ``ros``, ``mavlink``, ``dataflash``, ``ulog``,
        ``moos`` or ``csv``."""

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        """``fmt``: what `recognise` said, so that the log is recognised once."""
        ...

    def inventory(self, path: Path, fmt: str) -> LogInventory: ...


# Each format's adapter as (module, class).
_ADAPTERS: dict[str, tuple[str, str]] = {
    "bag": ("adapters.rosbag", "RosbagAdapter"),
    "db3": ("adapters.rosbag2_sqlite", "Db3Adapter"),
    "ros2-mcap": ("adapters.mcap", "Ros2McapAdapter"),
    "mcap": ("adapters.mcap", "McapAdapter"),
    "tlog": ("adapters.mavlink", "TlogAdapter"),
    "bin": ("adapters.mavlink", "DataflashAdapter"),
    "ulog": ("adapters.ulog", "UlogAdapter"),
    "csv": ("adapters.csv_log", "CsvAdapter"),
    "topic-csv": ("adapters.topic_csv", "TopicCsvAdapter"),
    "alog": ("adapters.moos_alog", "MoosAlogAdapter"),
}


@cache
def _adapter_of(fmt: str) -> Adapter:
    module, name = _ADAPTERS[fmt]
    return cast(Adapter, getattr(import_module(module), name)())


def detect_format(path: Path) -> str:
    """Return the format name of the log at ``path`` from its content."""
    if not path.exists():
        raise LogError(path, "no such file or directory")
    if path.is_file() and path.stat().st_size == 0:
        raise LogError(path, "empty file")
    fmt = recognise(path)
    if fmt is None:
        raise LogError(path, f"not a log this tool reads (known formats: "
                             f"{', '.join(KNOWN_FORMATS)})")
    return fmt


def _find_adapter(path: Path) -> tuple[Adapter, str]:
    fmt = detect_format(path)
    return _adapter_of(fmt), fmt


def read_log(path: Path, sources: Mapping[str, LogSources]) -> Signals:
    """Read the log at ``path`` with the mapping of its family (``sources[family]``)."""
    adapter, fmt = _find_adapter(path)
    mapping = sources.get(adapter.family)
    if mapping is None:
        raise LogError(path, f"the profile has no [sources.{adapter.family}] mapping for "
                             f"{fmt} logs")
    return adapter.read(path, mapping, fmt)


def inventory(path: Path) -> tuple[LogInventory, str]:
    """What the log at ``path`` holds, and the profile family that maps its signals."""
    adapter, fmt = _find_adapter(path)
    return adapter.inventory(path, fmt), adapter.family


def with_ros_words(path: Path, contents: LogInventory) -> LogInventory:
    """``contents`` (a ROS log's inventory) with the log's own words (`adapters.ros_words`),
    which its index does not hold: read from their topics alone, under whatever namespace
    they are; none where they do not read. Only for showing them: it decodes those topics."""
    words = words_among(topic.name for topic in contents.topics)
    if not words:
        return contents
    try:
        said = read_log(path, {"ros": LogSources({}, namespace="", words=words)})
    except LogError:
        return contents
    return replace(contents, autopilot_messages=said.autopilot_messages)
