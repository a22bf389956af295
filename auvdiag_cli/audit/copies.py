"""A log named after another beside it (``run.1.bin`` beside ``run.bin``) is judged by its
content: the same bytes, or the first bytes of the other (a download cut short), or the same
stretch of time on the logs' absolute clocks (the dive recorded again, in another format or
by another recorder) make it a copy, not a dive of its own; anything else (a continuation,
another dive) is a dive. So is a log file inside a folder of per-topic CSVs over the same
time: the bag the folder was exported from."""

from collections.abc import Sequence
from pathlib import Path

from adapters import inventory
from auvdiag_errors import AuvdiagError

BLOCK = 1 << 20
# Clocks since boot count from zero; a start after 2001 is an absolute (epoch) time.
ABSOLUTE_CLOCK_NS = 978_307_200 * 10**9
SAME_RECORDING = 0.5     # shared time, as a share of the shorter log's span


def copies(logs: Sequence[Path]) -> dict[Path, str]:
    """The logs of ``logs`` that are copies of another, each with why (naming the other)."""
    found = _exported_from(logs)
    by_folder: dict[Path, dict[str, Path]] = {}
    for log in logs:
        if log.is_file():
            by_folder.setdefault(log.parent, {})[log.stem] = log
    for log in logs:
        parts = log.name.split(".")
        beside = by_folder.get(log.parent, {})
        for stem in (".".join(parts[:k]) for k in range(1, len(parts))):
            original = beside.get(stem)
            if original is None or original == log or original in found or log in found:
                continue
            judged = _copy(log, original)
            if judged is not None:
                found[judged[0]] = judged[1]
    return found


def _exported_from(logs: Sequence[Path]) -> dict[Path, str]:
    """A log file inside a folder that is itself a log (a folder of per-topic CSVs holding
    the bag they were exported from, as ALFA keeps its flights) over the same stretch of
    time: one flight in two formats, audited once, as the folder."""
    folders = {log.resolve() for log in logs if log.is_dir()}
    found: dict[Path, str] = {}
    for log in logs:
        if log.is_file() and log.parent.resolve() in folders:
            shared = _shared_time(log, log.parent)
            if shared is not None and shared >= SAME_RECORDING:
                found[log] = (f"the same recording as the folder it lies in, {log.parent.name} "
                              f"({shared:.0%} of its time span on the same clock)")
    return found


def _copy(named: Path, original: Path) -> tuple[Path, str] | None:
    """Which of the two is the copy, and why; None for two dives."""
    shorter, longer = sorted((named, original), key=lambda p: (p.stat().st_size, p != named))
    if _starts_with(longer, shorter):
        if shorter.stat().st_size == longer.stat().st_size:
            return named, f"a copy of {original.name} (the same bytes)"
        return shorter, (f"the first {shorter.stat().st_size} bytes of {longer.name} "
                         "(a copy cut short)")
    shared = _shared_time(named, original)
    if shared is not None and shared >= SAME_RECORDING:
        return named, (f"the same recording as {original.name} ({shared:.0%} of its time "
                       "span on the same clock)")
    return None


def _starts_with(longer: Path, shorter: Path) -> bool:
    with longer.open("rb") as whole, shorter.open("rb") as start:
        while block := start.read(BLOCK):
            if whole.read(len(block)) != block:
                return False
    return True


def _shared_time(first: Path, second: Path) -> float | None:
    """The time both logs cover, as a share of the shorter one's span; None where either
    has no absolute clock (or cannot be read)."""
    spans = [_absolute_span(log) for log in (first, second)]
    if spans[0] is None or spans[1] is None:
        return None
    (start_a, end_a), (start_b, end_b) = spans[0], spans[1]
    shortest = min(end_a - start_a, end_b - start_b)
    shared = min(end_a, end_b) - max(start_a, start_b)
    return max(shared, 0) / shortest if shortest > 0 else None


def _absolute_span(log: Path) -> tuple[int, int] | None:
    try:
        held = inventory(log)[0]
    except (AuvdiagError, OSError):
        return None
    if held.start_ns is None or held.end_ns is None or held.start_ns < ABSOLUTE_CLOCK_NS:
        return None
    return held.start_ns, held.end_ns
