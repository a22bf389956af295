"""Resolve a field path such as ``twist.linear.x`` or ``data[1]`` on a decoded message."""

import re
from collections.abc import Callable
from functools import lru_cache
from typing import Any

_STEP = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")


@lru_cache(maxsize=256)
def parse_field_path(path: str) -> tuple[str | int, ...]:
    """Split a dotted path with list indices into attribute names and integer indices."""
    steps: list[str | int] = []
    for part in path.split("."):
        if not part:
            raise ValueError(f"empty step in field path {path!r}")
        matched_to = 0
        for match in _STEP.finditer(part):
            if match.start() != matched_to:
                break
            name, index = match.groups()
            steps.append(name if name is not None else int(index))
            matched_to = match.end()
        if matched_to != len(part):
            raise ValueError(f"cannot parse field path {path!r} near {part[matched_to:]!r}")
    return tuple(steps)


def is_field_path(path: str) -> bool:
    """Whether ``path`` parses (a damaged log's field names may not)."""
    try:
        parse_field_path(path)
    except ValueError:
        return False
    return True


def field_getter(path: str) -> Callable[[Any], Any]:
    """Return a function that extracts ``path`` from a message object or a mapping."""
    steps = parse_field_path(path)

    def get(message: Any) -> Any:
        value = message
        for step in steps:
            if isinstance(step, int) or isinstance(value, dict):
                value = value[step]
            else:
                value = getattr(value, step)
        return value

    return get

