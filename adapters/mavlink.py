"""MAVLink telemetry logs (.tlog) and ArduPilot DataFlash logs (.bin) through pymavlink.

Only the message types the profile names are decoded (pymavlink's type filter). A tlog's
times are the ground station's receive times; a DataFlash log's are the autopilot's TimeUS
(µs since boot)."""

import contextlib
import io
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

from adapters.collect import SignalCollector
from adapters.errors import LogError
from adapters.inventory import LogInventory, TopicInfo
from adapters.mavlink_scan import RecordScan, scan_file
from adapters.signals import LogSources, Signals

MAVLINK_MAGICS = (0xFE, 0xFD)            # MAVLink 1 and 2 frame start
PLAUSIBLE_EPOCH_US = (946_684_800_000_000, 4_102_444_800_000_000)   # years 2000 … 2100
DATAFLASH_HEADER = b"\xa3\x95\x80"       # record header + FMT type


def _read_messages(path: Path, reader: Any, collector: SignalCollector,
                   time_ns: Callable[[Any], int]) -> None:
    """Feed the wanted messages to the collector; keep what precedes any damage."""
    wanted = sorted(collector.topics)
    try:
        while (message := reader.recv_match(type=wanted, blocking=False)) is not None:
            collector.add(message.get_type(), time_ns(message), message)
    except LogError:
        raise
    except Exception as error:  # pymavlink raises assorted types on damaged records
        if collector.count == 0:
            raise LogError(path, f"damaged log: {error}") from None
        collector.notes.append(f"log damaged after {collector.count} messages ({error}); "
                               "analysed the part before the damage")


@contextlib.contextmanager
def _quiet() -> Any:
    """pymavlink prints 'bad header' and progress to stdout/stderr; a library must not."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        yield


class TlogAdapter:
    family = "mavlink"
    formats = ("tlog",)

    def sniff(self, path: Path) -> str | None:
        if not path.is_file():
            return None
        with path.open("rb") as stream:
            head = stream.read(9)
        if len(head) < 9 or head[8] not in MAVLINK_MAGICS:
            return None
        (time_us,) = struct.unpack(">Q", head[:8])
        return "tlog" if PLAUSIBLE_EPOCH_US[0] < time_us < PLAUSIBLE_EPOCH_US[1] else None

    def read(self, path: Path, sources: LogSources) -> Signals:
        from pymavlink import mavutil

        collector = SignalCollector(path, sources)
        with path.open("rb") as stream:
            (first_us,) = struct.unpack(">Q", stream.read(8))
        with _quiet():
            try:
                reader = mavutil.mavmmaplog(str(path))
            except Exception as error:  # pymavlink's index build fails in assorted ways
                raise LogError(path, f"cannot open tlog: {error}") from None
            try:
                # The low bits of the record time carry a link id; whole µs are enough here.
                _read_messages(path, reader, collector,
                               lambda m: round(m._timestamp * 1e6) * 1000)
            finally:
                reader.close()
        return _finish(collector, "tlog", first_us * 1000,
                       scan_file(path, "tlog", _message_names()), "MAVLink")

    def inventory(self, path: Path) -> LogInventory:
        return _inventory("tlog", scan_file(path, "tlog", _message_names()), "MAVLink")


class DataflashAdapter:
    family = "dataflash"
    formats = ("bin",)

    def sniff(self, path: Path) -> str | None:
        if not path.is_file():
            return None
        with path.open("rb") as stream:
            return "bin" if stream.read(3) == DATAFLASH_HEADER else None

    def read(self, path: Path, sources: LogSources) -> Signals:
        from pymavlink import DFReader

        collector = SignalCollector(path, sources)
        with _quiet():
            try:
                reader = DFReader.DFReader_binary(str(path), zero_time_base=True)
            except Exception as error:  # the indexer fails in assorted ways on damage
                raise LogError(path, f"cannot open DataFlash log: {error}") from None
            _read_messages(path, reader, collector, lambda m: int(m.TimeUS) * 1000)
        return _finish(collector, "bin", None, scan_file(path, "bin"), "DataFlash")

    def inventory(self, path: Path) -> LogInventory:
        return _inventory("bin", scan_file(path, "bin"), "DataFlash")


def _finish(collector: SignalCollector, fmt: str, start_ns: int | None, scan: RecordScan,
            kind: str) -> Signals:
    """The record walk names the message types and says where the file breaks, if it does."""
    if scan.problem:
        collector.notes.append(scan.problem)
    return collector.finish(fmt, start_ns, None, {name: kind for name in scan.counts})


def _message_names() -> dict[int, str]:
    from pymavlink.dialects.v20 import ardupilotmega

    return {msgid: cls.msgname for msgid, cls in ardupilotmega.mavlink_map.items()}


def _inventory(fmt: str, scan: RecordScan, kind: str) -> LogInventory:
    return LogInventory(
        fmt, None if scan.first_us is None else scan.first_us * 1000,
        None if scan.last_us is None else scan.last_us * 1000,
        [TopicInfo(name, kind, count) for name, count in sorted(scan.counts.items())],
        [scan.problem] if scan.problem else [])
