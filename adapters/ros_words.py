"""What a ROS vehicle's own software said during a log: its nodes' log messages (`/rosout`,
ROS 1 `rosgraph_msgs/Log` or ROS 2 `rcl_interfaces/msg/Log`), its autopilot's texts as
mavros republishes them (`mavros/statustext/recv`, with MAVLink's severity) and its
hardware's status (`/diagnostics`: each status that worsens while the log runs, from OK to
a warning or an error, is news; one that stands as it was when the log began is not: a
battery monitor set up wrong can warn "low voltage" all along). Read beside the profile's
signals wherever a ROS log holds them; a message that does not read says nothing, and none
makes a log unreadable."""

from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import Any

from adapters.signals import AutopilotMessage, WordSource, as_text

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
# A hardware status's level (diagnostic_msgs/DiagnosticStatus: OK, WARN, ERROR, STALE: no
# news from it) as MAVLink's severity; WARN, as a node's, by its words.
STATUS_LEVELS = ((0, 6), (1, None), (2, 3), (3, 4))
OK_LEVEL = 0
DIAGNOSTICS = WordSource("/diagnostics", "message", "level", node="name", at_root=True,
                         severities=STATUS_LEVELS, statuses="status")
# The aggregator's hierarchy of the same statuses.
DIAGNOSTICS_AGGREGATED = replace(DIAGNOSTICS, topic="/diagnostics_agg",
                                 only_without="/diagnostics")
ROS_WORD_SOURCES = (ROSOUT, ROSOUT_AGGREGATED, STATUSTEXT, DIAGNOSTICS, DIAGNOSTICS_AGGREGATED)
MAVLINK_SEVERITIES = range(8)
MAX_STATUSES = 32          # of one message's statuses, read from a column-wise export


def words_among(topics: Iterable[str]) -> tuple[WordSource, ...]:
    """The sources of words among a log's ``topics``, each under the name the log gives it
    (a vehicle's namespace included)."""
    found = []
    for topic in topics:
        for source in ROS_WORD_SOURCES:
            if topic == source.topic or (not source.at_root and topic.endswith(source.topic)):
                found.append(replace(source, topic=topic, at_root=True))
    return tuple(found)


def word_paths(source: WordSource) -> list[str]:
    """The field paths a source's words are read from (a status array's, index by index: a
    per-topic CSV export has a column for each)."""
    own = [source.text, source.level, *([source.node] if source.node else [])]
    if source.statuses is None:
        return own
    return [f"{source.statuses}[{index}].{path}" for index in range(MAX_STATUSES)
            for path in own]


def severity(source: WordSource, level: Any) -> int | None:
    """The message's level as MAVLink's severity (None: not one the source defines)."""
    try:
        number = int(level)
    except (TypeError, ValueError, OverflowError):
        return None
    if source.severities is None:
        return number if number in MAVLINK_SEVERITIES else None
    return dict(source.severities).get(number)


class WordsRead:
    """The words of each source as a reader meets them, in the log's time order at the end."""

    def __init__(self) -> None:
        self.by_source: dict[WordSource, list[AutopilotMessage]] = {}
        self.status_levels: dict[tuple[WordSource, str], int] = {}    # each status's last

    def add(self, source: WordSource, time_ns: int, text: Any, level: Any,
            node: Any = None) -> None:
        self._said(source, time_ns, as_text(text), as_text(node) if node is not None else "",
                   severity(source, level))

    def _said(self, source: WordSource, time_ns: int, text: str, speaker: str,
              level: int | None, standing: bool = False) -> None:
        if text:
            self.by_source.setdefault(source, []).append(AutopilotMessage(
                time_ns, f"{speaker}: {text}" if speaker else text, level, standing))

    def add_status(self, source: WordSource, time_ns: int, text: Any, level: Any,
                   node: Any) -> None:
        """One status of a status array: news only where it is worse than it last was; one
        already wrong at its first report stands from the log's start."""
        try:
            number = int(level)
        except (TypeError, ValueError, OverflowError):
            return
        speaker = as_text(node)
        before = self.status_levels.get((source, speaker))
        self.status_levels[source, speaker] = number
        if number > (OK_LEVEL if before is None else before):
            self._said(source, time_ns, as_text(text) or "(no message)", speaker,
                       severity(source, number), standing=before is None)

    def add_message(self, source: WordSource, time_ns: int, message: Any,
                    get: Callable[[Any, str], Any]) -> None:
        """One decoded message; ``get(message, path)`` reads a field (raising where the
        message lacks it: then it says nothing)."""
        try:
            if source.statuses is None:
                node = get(message, source.node) if source.node else None
                self.add(source, time_ns, get(message, source.text),
                         get(message, source.level), node)
                return
            for status in get(message, source.statuses):
                self.add_status(source, time_ns, get(status, source.text),
                                get(status, source.level),
                                get(status, source.node) if source.node else None)
        except (AttributeError, IndexError, KeyError, TypeError, ValueError):
            return

    def add_columns(self, source: WordSource, times_ns: Any, column: Callable[[str], Any]
                    ) -> None:
        """Every message of the source's topic at once, as columns (a node's name and a
        level, repeated on most messages, read once each)."""
        if source.statuses is not None:
            self._status_columns(source, times_ns, column)
            return
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

    def _status_columns(self, source: WordSource, times_ns: Any,
                        column: Callable[[str], Any]) -> None:
        """A status array as columns, index by index (a message with fewer statuses has
        empty cells there), each message's statuses in turn."""
        paths = word_paths(source)
        width = len(paths) // MAX_STATUSES
        statuses = []
        for first in range(0, len(paths), width):
            try:
                statuses.append([column(path).tolist() for path in paths[first:first + width]])
            except (IndexError, KeyError, TypeError, ValueError):
                break
        for row, time_ns in enumerate(times_ns.tolist()):
            for status in statuses:
                self.add_status(source, time_ns, *(cells[row] for cells in status),
                                *([] if source.node else [None]))

    def messages(self) -> list[AutopilotMessage]:
        said_by = {source.topic for source, said in self.by_source.items() if said}
        kept = [message for source, said in self.by_source.items()
                if source.only_without not in said_by for message in said]
        return sorted(kept, key=lambda m: m.time_ns)
