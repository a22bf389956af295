"""`auvdiag init-profile --like PROFILE`: start from a profile of a similar vehicle and fit its
log mapping to this log. Each signal that does not resolve is moved to the closest field of
its message type that does; every change is written at the top of the draft, to be checked."""

import re
from dataclasses import replace
from pathlib import Path

from adapters import read_log
from adapters.fieldnames import closest_first
from adapters.signals import FieldSource
from auvdiag_cli.jobs.draft_text import quoted
from auvdiag_cli.jobs.inspect import SignalResolution, inspect_log
from auvdiag_cli.vehicle.profile import Profile, load_profile, profile_text
from auvdiag_errors import LogError, UsageError

CANDIDATES_TRIED = 3


def _section_line(text: str, family: str, name: str) -> int | None:
    """Index of the line mapping ``name`` in the family's [sources] tables."""
    lines, inside = text.splitlines(), False
    for number, line in enumerate(lines):
        header = re.match(r"\s*\[([^\]]+)\]", line)
        if header:
            inside = header.group(1).startswith(f"sources.{family}")
        elif inside and re.match(rf"\s*{re.escape(name)}\s*=\s*\{{", line):
            return number
    return None


def _moved(text: str, family: str, name: str, old: str, new: str) -> str:
    number = _section_line(text, family, name)
    if number is None:
        raise UsageError(f"cannot find the mapping of {name} in [sources.{family}]")
    lines = text.splitlines()
    key = "column" if family == "csv" else "field"
    for written in (quoted(old), f"'{old}'"):      # a basic or a literal TOML string
        lines[number] = lines[number].replace(f"{key} = {written}", f"{key} = {quoted(new)}")
    return "\n".join(lines) + "\n"


def _refits(path: Path, profile: Profile, family: str,
            unread: list[tuple[SignalResolution, tuple[str, ...]]]) -> dict[str, str | None]:
    """Per signal that did not resolve (with the fields of its message type), the closest
    of those fields that reads on this log, or None: every candidate tried in one pass."""
    sources = profile.sources[family]
    tried: dict[str, list[tuple[str, str]]] = {}      # signal -> (read as, candidate)
    candidates = {}
    for signal, fields in unread:
        for rank, field in enumerate(closest_first(signal.field, fields)[:CANDIDATES_TRIED]):
            source = replace(sources.signals[signal.name], field=field)
            name = f"{signal.name}:{rank}"
            candidates[name] = replace(source, topic=field) if family == "csv" else source
            tried.setdefault(signal.name, []).append((name, field))

    def reads(chosen: dict[str, FieldSource], together: bool) -> set[str] | None:
        """Which of ``chosen`` read on the log (None: the log refuses them)."""
        try:
            return set(read_log(path, {family: replace(
                sources, signals=chosen, segment=None, optional=frozenset(chosen),
                tentative=together)}).series)
        except LogError:
            return None

    read = reads(candidates, True) if candidates else set()
    if read is None:        # refused together (instances to choose from): one at a time
        read = {name for name, source in candidates.items() if reads({name: source}, False)}
    return {signal.name: next((field for name, field in tried.get(signal.name, ())
                               if name in read), None) for signal, _ in unread}


def draft_like(path: Path, like: Path) -> str:
    """The text of ``like``'s profile, its mapping fitted to the log at ``path``."""
    profile = load_profile(like)
    text, where = profile_text(like)
    inspection = inspect_log(path, profile)
    family = inspection.family
    if not inspection.mapped:
        raise UsageError(f"{path}: profile {profile.name!r} has no [sources.{family}] mapping "
                         f"for {inspection.inventory.format} logs; draft without --like")
    fields = {t.name: t.fields or (t.name,) for t in inspection.inventory.topics}
    changes, lost = [], []
    unread = [(signal, fields.get(signal.topic, tuple(fields) if family == "csv" else ()))
              for signal in inspection.signals if not signal.resolved]
    refits = _refits(path, profile, family, unread)
    for signal, _ in unread:
        candidate = refits[signal.name]
        if candidate is None:
            lost.append(f"{signal.name} ({signal.problem})")
            continue
        text = _moved(text, family, signal.name, signal.field, candidate)
        changes.append(f"{signal.name}: {signal.topic} {signal.field} -> {candidate}")
    if lost:
        raise UsageError(f"{path}: with profile {profile.name!r}, {'; '.join(lost)}: no field "
                         "close to it reads on this log; draft without --like")
    header = [f"# Drafted by `auvdiag init-profile --like {like}` from {path.name}, starting "
              f"from {where}.",
              f"# {len(inspection.signals) - len(changes)} of {len(inspection.signals)} "
              "signals read on the log as that profile maps them."]
    header += [f"# CHECK, moved to the closest field: {change}" for change in changes]
    header += [f"# CHECK: {warning}" for warning in inspection.warnings]
    return "\n".join(header) + "\n\n" + text
