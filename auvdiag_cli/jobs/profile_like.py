"""`auvdiag init-profile --like PROFILE`: start from a profile of a similar vehicle and fit its
log mapping to this log. Each signal that does not resolve is moved to the closest field of
its message type that does; every change is written at the top of the draft, to be checked."""

import re
from dataclasses import replace
from pathlib import Path

from adapters import read_log
from adapters.fieldnames import closest_first
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


def _refit(path: Path, profile: Profile, family: str, signal: SignalResolution,
           fields: tuple[str, ...]) -> str | None:
    """The closest field of the signal's message type that reads on this log, or None."""
    sources = profile.sources[family]
    for candidate in closest_first(signal.field, fields)[:CANDIDATES_TRIED]:
        source = replace(sources.signals[signal.name], field=candidate)
        if family == "csv":
            source = replace(source, topic=candidate)
        try:
            read_log(path, {family: replace(sources, signals={signal.name: source},
                                            segment=None)})
        except LogError:
            continue
        return candidate
    return None


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
    for signal in inspection.signals:
        if signal.resolved:
            continue
        candidate = _refit(path, profile, family, signal,
                           fields.get(signal.topic, tuple(fields) if family == "csv" else ()))
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
