"""How an effort check says what it found: how much more of the effort a suspect carries,
and how large a weakness the normal logs let a log's shares show."""

from collections.abc import Sequence
from typing import Protocol


class SaidEffort(Protocol):
    """What is said of one actuator's effort (`effort_naming.ActuatorEffort`)."""

    @property
    def said(self) -> str: ...

    @property
    def group(self) -> str: ...

    @property
    def share(self) -> float | None: ...

    @property
    def normal_share(self) -> float | None: ...

    @property
    def spread(self) -> float | None: ...

    @property
    def departure(self) -> float | None: ...

    @property
    def since_onset(self) -> float | None: ...

    @property
    def smallest_rise_shown(self) -> float | None: ...


def carries(actuator: SaidEffort) -> str:
    """How much more of the effort a suspect carries: than on normal logs over the whole log;
    where its group changed within the log, first since then against before."""
    a = actuator
    figures = f"{a.share:.3f} against {a.normal_share:.3f} ± {a.spread:.3f}"
    if a.since_onset is None:
        return (f"{a.said} carries {more(a.departure)} of the effort than on normal logs "
                f"({figures})")
    return (f"{a.said} carries {more(a.since_onset)} of the effort since the change than "
            f"before it in this log (over the whole log, {more(a.departure)} than on normal "
            f"logs: {figures})")


def more(change: float | None) -> str:
    """"12% more", "3% less" (not "-3% more"): a share's relative change."""
    change = 0.0 if change is None or round(change, 2) == 0 else change
    return f"{abs(change):.0%} {'less' if change < 0 else 'more'}"


def smallest_rise_shown(actuators: Sequence[SaidEffort]) -> str:
    """What the normal logs let this log's shares show: with few of them, a weakness must
    be large to stand out."""
    by_group: dict[str, list[float]] = {}
    for a in actuators:
        if a.smallest_rise_shown is not None:
            by_group.setdefault(a.group, []).append(a.smallest_rise_shown)
    if not by_group:
        return ""
    said = [rise_range(rises) + ("" if len(by_group) == 1 else f" ({group})")
            for group, rises in by_group.items()]
    return (f"; against these normal logs, one weak actuator shows over this log once it "
            f"carries about {' or '.join(said)} more than its share")


def rise_range(rises: Sequence[float]) -> str:
    """"8%", or "8%-10%" where the members differ."""
    low, high = min(rises), max(rises)
    return f"{low:.0%}" if round(low, 2) == round(high, 2) else f"{low:.0%}-{high:.0%}"
