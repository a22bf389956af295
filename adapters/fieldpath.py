"""Resolve a field path such as ``twist.linear.x``, ``data[1]`` or ``rotors["motor-1"]`` on a
decoded message. A key that is not a plain name (a JSON message's ``motor-1``, ``rpm 2``) is
written quoted in brackets, as a JSON string."""

import json
import re
from collections.abc import Callable
from functools import lru_cache
from typing import Any

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_INDEX = re.compile(r"\[(\d+)\]")
_KEY = re.compile(r'\[("(?:[^"\\]|\\.)*")\]')


def _bracket(path: str, at: int) -> tuple[str | int, int] | None:
    """The ``[2]`` or ``["key"]`` step at ``at`` and where it ends, or None."""
    index = _INDEX.match(path, at)
    if index:
        return int(index.group(1)), index.end()
    key = _KEY.match(path, at)
    if key:
        try:
            return str(json.loads(key.group(1))), key.end()
        except ValueError:
            return None
    return None


@lru_cache(maxsize=256)
def parse_field_path(path: str) -> tuple[str | int, ...]:
    """Split a path into attribute names or keys (str) and list indices (int): names joined
    by dots, each step followed by any ``[index]`` or ``["key"]``; a path may begin with a
    bracketed key."""
    steps: list[str | int] = []
    at = 0
    while True:
        name = _NAME.match(path, at)
        if name:
            steps.append(name.group())
            at = name.end()
        elif not (at == 0 and path.startswith('["')):
            if at == len(path) or path[at] == ".":
                raise ValueError(f"empty step in field path {path!r}")
            raise ValueError(f"cannot parse field path {path!r} near {path[at:]!r}")
        while (bracket := _bracket(path, at)) is not None:
            steps.append(bracket[0])
            at = bracket[1]
        if at == len(path):
            return tuple(steps)
        if path[at] != ".":
            raise ValueError(f"cannot parse field path {path!r} near {path[at:]!r}")
        at += 1


def is_field_path(path: str) -> bool:
    """Whether ``path`` parses (a damaged log's field names may not)."""
    try:
        parse_field_path(path)
    except ValueError:
        return False
    return True


def join_step(prefix: str, name: str) -> str:
    """``prefix`` followed by the step ``name``: dotted where it is a plain name, else quoted
    in brackets (``rotors["motor-1"]``)."""
    if _NAME.fullmatch(name):
        return f"{prefix}.{name}" if prefix else name
    return f"{prefix}[{json.dumps(name, ensure_ascii=False)}]"


def field_getter(path: str) -> Callable[[Any], Any]:
    """Return a function that extracts ``path`` from a message object or a mapping."""
    steps = parse_field_path(path)

    def get(message: Any) -> Any:
        value = message
        for step in steps:
            if value is None:        # a JSON null or an unset message on the way: no reading
                return None
            if isinstance(step, int) or isinstance(value, dict):
                value = value[step]
            else:
                value = getattr(value, step)
        return value

    return get


def field_of(message: Any, path: str) -> Any:
    return field_getter(path)(message)


def resolves(message: Any, path: str) -> bool:
    """Whether ``message`` has a value at ``path``."""
    try:
        field_of(message, path)
    except (AttributeError, IndexError, KeyError, TypeError, ValueError):
        return False
    return True
