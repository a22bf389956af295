"""Whether the whole log was read, or only the part before damage (a salvaged log). Scripts
read this from the report instead of parsing notes; audits can count salvage as failure."""

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from adapters import Signals


@dataclass(frozen=True)
class Completeness:
    complete: bool
    bytes_total: int                 # the log's size on disk (a bag directory: its files)
    bytes_read: int | None           # where the readable part ends, when the reader knows
    messages_read: int               # messages of the profile's topics that were used
    seconds_read: float              # span of the readable part
    reason: str | None               # what stopped the reading (None when complete)

    @property
    def status(self) -> str:
        return "complete" if self.complete else "partial"

    def to_dict(self) -> dict[str, Any]:
        return {"status": self.status, "bytes_total": self.bytes_total,
                "bytes_read": self.bytes_total if self.complete else self.bytes_read,
                "messages_read": self.messages_read,
                "seconds_read": round(self.seconds_read, 3),
                "damage_at_byte": None if self.complete else self.bytes_read,
                "reason": self.reason}


def _size_on_disk(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.iterdir() if p.is_file())
    return path.stat().st_size


def completeness_of(signals: Signals) -> Completeness:
    damage = signals.damage
    return Completeness(
        complete=damage is None, bytes_total=_size_on_disk(signals.path),
        bytes_read=None if damage is None else damage.at_byte,
        messages_read=signals.messages_read,
        seconds_read=max(0.0, (signals.end_ns - signals.start_ns) / 1e9),
        reason=None if damage is None else damage.reason)
