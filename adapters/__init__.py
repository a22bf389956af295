"""Log adapters: one per format family, chosen by content, all producing `Signals`."""

from collections.abc import Mapping
from pathlib import Path
from typing import Protocol

from adapters.csv_log import CsvAdapter
from adapters.inventory import LogInventory, TopicInfo
from adapters.mavlink import DataflashAdapter, TlogAdapter
from adapters.mcap import McapAdapter
from adapters.rosbag import RosbagAdapter
from adapters.signals import FieldSource, LogSources, SegmentMarker, SegmentSource, Signals
from adapters.ulog import UlogAdapter
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
]


class Adapter(Protocol):
    """One format family: recognises its files by content and reads the needed signals."""

    @property
    def family(self) -> str:
        """Which profile mapping it reads: ``ros``, ``mavlink``, ``dataflash``, ``ulog`` or
        ``csv``."""

    @property
    def formats(self) -> tuple[str, ...]: ...

    def sniff(self, path: Path) -> str | None: ...

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        """``fmt``: what `sniff` said, so that the log is recognised once."""
        ...

    def inventory(self, path: Path, fmt: str) -> LogInventory: ...


# Order matters: a ROS 2 bag's .mcap storage file is claimed as a bag before plain MCAP.
# CSV last: it is recognised by being text with a header, which the binary formats are not.
ADAPTERS: tuple[Adapter, ...] = (RosbagAdapter(), McapAdapter(), TlogAdapter(),
                                 DataflashAdapter(), UlogAdapter(), CsvAdapter())


def _find_adapter(path: Path) -> tuple[Adapter, str]:
    if not path.exists():
        raise LogError(path, "no such file or directory")
    if path.is_file() and path.stat().st_size == 0:
        raise LogError(path, "empty file")
    for adapter in ADAPTERS:
        fmt = adapter.sniff(path)
        if fmt is not None:
            return adapter, fmt
    kinds = ", ".join(fmt for adapter in ADAPTERS for fmt in adapter.formats)
    raise LogError(path, f"not a log this tool reads (known formats: {kinds})")


def detect_format(path: Path) -> str:
    """Return the format name of the log at ``path`` from its content."""
    return _find_adapter(path)[1]


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
