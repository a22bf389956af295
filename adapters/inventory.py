"""What a log holds, for `auvdiag inspect`: topics or message types, counts, time span."""

from dataclasses import dataclass, field

from adapters.signals import AutopilotMessage


@dataclass(frozen=True)
class TopicInfo:
    name: str
    type: str
    count: int
    fields: tuple[str, ...] = ()                        # field paths a profile can name
    instances: tuple[tuple[str, tuple[str, ...]], ...] = ()   # instance key → its values
    names: tuple[str, ...] = ()                         # NAMED_VALUE_* names it carries


@dataclass
class LogInventory:
    format: str
    start_ns: int | None
    end_ns: int | None
    topics: list[TopicInfo]
    notes: list[str] = field(default_factory=list)
    # What the vehicle's own software said, over the whole log (formats that keep it).
    autopilot_messages: list[AutopilotMessage] = field(default_factory=list)

    @property
    def duration_s(self) -> float | None:
        if self.start_ns is None or self.end_ns is None:
            return None
        return (self.end_ns - self.start_ns) / 1e9


def merged_inventory(fmt: str, parts: list[LogInventory]) -> LogInventory:
    """One log stored in several files (a split ROS 2 bag): counts added, spans joined."""
    counts: dict[tuple[str, str], TopicInfo] = {}
    for part in parts:
        for topic in part.topics:
            known = counts.get((topic.name, topic.type))
            counts[topic.name, topic.type] = topic if known is None else TopicInfo(
                topic.name, topic.type, known.count + topic.count, known.fields or topic.fields)
    starts = [p.start_ns for p in parts if p.start_ns is not None]
    ends = [p.end_ns for p in parts if p.end_ns is not None]
    return LogInventory(fmt, min(starts, default=None), max(ends, default=None),
                        [counts[key] for key in sorted(counts)],
                        [note for part in parts for note in part.notes])
