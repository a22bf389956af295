"""ROS 1 bags and ROS 2 bags (sqlite3 or mcap storage, directory or bare storage file)."""

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from adapters.errors import LogError
from adapters.fieldpath import field_getter
from adapters.signals import LogSources, SegmentMarker, Signals

ROS1_MAGIC = b"#ROSBAG V2.0"
SQLITE_MAGIC = b"SQLite format 3\x00"
MCAP_MAGIC = b"\x89MCAP0\r\n"


def _head(path: Path, size: int) -> bytes:
    with path.open("rb") as stream:
        return stream.read(size)


def sniff_format(path: Path) -> str | None:
    """Name the rosbag flavour of ``path`` from its content, or None if it is not one."""
    if path.is_dir():
        storage = sorted(p for p in path.iterdir() if p.suffix in (".mcap", ".db3"))
        if (path / "metadata.yaml").is_file() and storage:
            return "ros2-mcap" if storage[0].suffix == ".mcap" else "db3"
        return None
    if not path.is_file():
        return None
    head = _head(path, 16)
    if head.startswith(ROS1_MAGIC):
        return "bag"
    if head.startswith(SQLITE_MAGIC):
        return "db3"
    if head.startswith(MCAP_MAGIC):
        return "ros2-mcap" if (path.parent / "metadata.yaml").is_file() else "mcap"
    return None


class RosbagAdapter:
    """Reads ROS 1 and ROS 2 bags through rosbags' AnyReader, decoding only the needed topics."""

    formats = ("bag", "db3", "ros2-mcap", "mcap")

    def sniff(self, path: Path) -> str | None:
        return sniff_format(path)

    def read(self, path: Path, sources: LogSources) -> Signals:
        from rosbags.highlevel import AnyReader

        fmt = sniff_format(path)
        if fmt is None:
            raise LogError(path, "not a ROS bag")
        try:
            reader = AnyReader([path])
            reader.open()
        except Exception as error:  # rosbags raises several unrelated types on damaged files
            raise LogError(path, f"cannot open {fmt} log: {error}") from None
        try:
            return self._extract(reader, path, fmt, sources)
        finally:
            reader.close()

    def _extract(self, reader: Any, path: Path, fmt: str, sources: LogSources) -> Signals:
        topics = {c.topic: c.msgtype for c in reader.connections}
        wanted = {src.topic for src in sources.signals.values()}
        if sources.segment_topic and sources.segment_topic in topics:
            wanted.add(sources.segment_topic)
        missing = sorted({src.topic for src in sources.signals.values()} - topics.keys())
        if missing:
            raise LogError(path, f"missing topic(s) {', '.join(missing)}")
        connections = [c for c in reader.connections if c.topic in wanted]
        getters = {
            name: (src, field_getter(src.field)) for name, src in sources.signals.items()
        }
        times: dict[str, list[int]] = {name: [] for name in getters}
        values: dict[str, list[float]] = {name: [] for name in getters}
        markers: list[SegmentMarker] = []
        count = 0
        try:
            for connection, timestamp, raw in reader.messages(connections=connections):
                message = reader.deserialize(raw, connection.msgtype)
                count += 1
                if connection.topic == sources.segment_topic:
                    markers.append(SegmentMarker(int(timestamp), str(message.data).strip()))
                    continue
                for name, (src, get) in getters.items():
                    if src.topic == connection.topic:
                        times[name].append(int(timestamp))
                        values[name].append(float(get(message)))
        except (AttributeError, IndexError, KeyError, TypeError) as error:
            raise LogError(path, f"field does not resolve: {error!r}") from None
        except Exception as error:  # damaged data surfaces as several unrelated types
            raise LogError(path, f"damaged after {count} messages: {error}") from None
        series = {}
        for name, (src, _) in getters.items():
            data = np.asarray(values[name], dtype=np.float64) * src.scale + src.offset
            series[name] = pd.Series(data, index=np.asarray(times[name], dtype=np.int64), name=name)
        empty = sorted(name for name, s in series.items() if s.empty)
        if empty:
            raise LogError(path, f"no messages for signal(s) {', '.join(empty)}")
        return Signals(
            path=path,
            format=fmt,
            start_ns=int(reader.start_time),
            end_ns=int(reader.end_time),
            series=series,
            markers=markers,
            topics=topics,
        )
