"""The typed report to and from JSON, field by field: a dataclass becomes an object whose
keys are its field names in their order (so the JSON reads as the fields are declared),
a tuple a list, a mapping an object; back again by each field's type. A key that an older
report lacks takes the field's default; keys the fields do not name are ignored."""

import dataclasses
import types
import typing
from collections.abc import Mapping
from functools import cache
from typing import Any, TypeVar

Part = TypeVar("Part")


def to_plain(value: object) -> object:
    """What json.dumps writes for ``value``."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple | list):
        return [to_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): to_plain(v) for k, v in value.items()}
    return value


@cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _convert(kind: Any, value: object) -> object:
    if value is None:
        return None
    origin, arguments = typing.get_origin(kind), typing.get_args(kind)
    if origin in (typing.Union, types.UnionType):
        present = [a for a in arguments if a is not type(None)]
        return _convert(present[0], value) if len(present) == 1 else value
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ValueError(f"expected a list, got {type(value).__name__}")
        item = arguments[0] if arguments else Any
        return tuple(_convert(item, v) for v in value)
    if origin in (dict, Mapping, typing.Mapping):
        if not isinstance(value, Mapping):
            raise ValueError(f"expected an object, got {type(value).__name__}")
        item = arguments[1] if len(arguments) == 2 else Any
        return {str(k): _convert(item, v) for k, v in value.items()}
    if isinstance(kind, type) and dataclasses.is_dataclass(kind):
        return from_plain(kind, value)
    return value


def from_plain(cls: type[Part], data: object) -> Part:
    """``cls`` (a dataclass) from what json.loads gave; ValueError where a required key is
    missing or a value is of the wrong shape."""
    if not isinstance(data, Mapping):
        raise ValueError(f"{cls.__name__}: expected an object, got {type(data).__name__}")
    hints, given = _hints(typing.cast(type, cls)), {}
    for f in dataclasses.fields(cls):  # type: ignore[arg-type]
        if f.name in data:
            given[f.name] = _convert(hints[f.name], data[f.name])
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ValueError(f"{cls.__name__}: no '{f.name}'")
    return cls(**given)
