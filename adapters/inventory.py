"""What a log holds, for `auvdiag inspect`: topics or message types, counts, time span."""

from dataclasses import dataclass, field


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

    @property
    def duration_s(self) -> float | None:
        if self.start_ns is None or self.end_ns is None:
            return None
        return (self.end_ns - self.start_ns) / 1e9
