"""What a ROS vehicle's own software said during a log: its nodes' log messages (`/rosout`,
ROS 1 `rosgraph_msgs/Log` or ROS 2 `rcl_interfaces/msg/Log`) and its autopilot's texts as
mavros republishes them (`mavros/statustext/recv`, with MAVLink's severity). Read beside
the profile's signals wherever a ROS log holds them; a message that does not read says
nothing, and none makes a log unreadable."""

from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import Any

from adapters.signals import AutopilotMessage, WordSource

# A node's level as MAVLink's severity (syslog's: 2 critical, 3 error, 6 info, 7 debug).
# WARN stays without one: nodes warn of routine things (a late transform, a dropped
# frame) as readily as of trouble, so its words decide, as for a DataFlash MSG record.
NODE_LEVELS = ((1, 7), (2, 6), (4, None), (8, 3), (16, 2),           # ROS 1: 1 … 16
               (10, 7), (20, 6), (30, None), (40, 3), (50, 2))       # ROS 2: 10 … 50
ROSOUT = WordSource("/rosout", "msg", "level", node="name", at_root=True,
                    severities=NODE_LEVELS)
# What the rosout node republishes from every node: the same messages again where a
# recording took both, so read only where `/rosout` gave none.
ROSOUT_AGGREGATED = WordSource("/rosout_agg", "msg", "level", node="name", at_root=True,
                               severities=NODE_LEVELS, only_without="/rosout")
STATUSTEXT = WordSource("/mavros/statustext/recv", "text", "severity")
ROS_WORD_SOURCES = (ROSOUT, ROSOUT_AGGREGATED, STATUSTEXT)
MAVLINK_SEVERITIES = range(8)


def words_among(topics: Iterable[str]) -> tuple[WordSource, ...]:
    """The sources of words among a log's ``topics``, each under the name the log gives it
    (a vehicle's namespace included)."""
    found = []
    for topic in topics:
        for source in ROS_WORD_SOURCES:
            if topic == source.topic or (not source.at_root and topic.endswith(source.topic)):
                found.append(replace(source, topic=topic, at_root=True))
    return tuple(found)


def severity(source: WordSource, level: Any) -> int | None:
    """The message's level as MAVLink's severity (None: not one the source defines)."""
    try:
        number = int(level)
    except (TypeError, ValueError):
        return None
    if source.severities is None:
        return number if number in MAVLINK_SEVERITIES else None
    return dict(source.severities).get(number)


def as_text(value: Any) -> str:
    if isinstance(value, bytes):
        value = value.split(b"\0", 1)[0].decode("utf-8", "replace")
    return str(value).rstrip("\0").strip()


class WordsRead:
    """The words of each source as a reader meets them, in the log's time order at the end."""

    def __init__(self) -> None:
        self.by_source: dict[WordSource, list[AutopilotMessage]] = {}

    def add(self, source: WordSource, time_ns: int, text: Any, level: Any,
            node: Any = None) -> None:
        self._said(source, time_ns, as_text(text), as_text(node) if node is not None else "",
                   severity(source, level))

    def _said(self, source: WordSource, time_ns: int, text: str, speaker: str,
              level: int | None) -> None:
        if text:
            self.by_source.setdefault(source, []).append(AutopilotMessage(
                time_ns, f"{speaker}: {text}" if speaker else text, level))

    def add_message(self, source: WordSource, time_ns: int, message: Any,
                    get: Callable[[Any, str], Any]) -> None:
        """One decoded message; ``get(message, path)`` reads a field (raising where the
        message lacks it: then it says nothing)."""
        try:
            node = get(message, source.node) if source.node else None
            self.add(source, time_ns, get(message, source.text), get(message, source.level),
                     node)
        except (AttributeError, IndexError, KeyError, TypeError, ValueError):
            return

    def add_columns(self, source: WordSource, times_ns: Any, column: Callable[[str], Any]
                    ) -> None:
        """Every message of the source's topic at once, as columns (a node's name and a
        level, repeated on most messages, read once each)."""
        try:
            texts, levels = column(source.text).tolist(), column(source.level).tolist()
            nodes = column(source.node).tolist() if source.node else [None] * len(texts)
        except (IndexError, KeyError, TypeError, ValueError):
            return
        severities = {level: severity(source, level) for level in set(levels)}
        speakers = {node: "" if node is None else as_text(node) for node in set(nodes)}
        for time_ns, text, level, node in zip(times_ns.tolist(), texts, levels, nodes,
                                              strict=True):
            self._said(source, time_ns, as_text(text), speakers[node], severities[level])

    def messages(self) -> list[AutopilotMessage]:
        said_by = {source.topic for source, said in self.by_source.items() if said}
        kept = [message for source, said in self.by_source.items()
                if source.only_without not in said_by for message in said]
        return sorted(kept, key=lambda m: m.time_ns)
