"""Typed access to parsed TOML tables, with every error naming the full key."""

from typing import Any

from auvdiag_errors import ProfileError


class TableReader:
    """A TOML table and its dotted location, for errors that name the key."""

    def __init__(self, table: dict[str, Any], where: str) -> None:
        self.table = table
        self.where = where

    def key(self, name: str) -> str:
        return f"{self.where}.{name}" if self.where else name

    def get(self, name: str, kind: type | tuple[type, ...], default: Any = ...) -> Any:
        if name not in self.table:
            if default is ...:
                raise ProfileError(f"missing key '{self.key(name)}'")
            return default
        value = self.table[name]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
            raise ProfileError(f"key '{self.key(name)}' must be {_kind_name(kind)}, got {value!r}")
        return value

    def sub(self, name: str) -> "TableReader":
        return TableReader(self.get(name, dict), self.key(name))

    def items(self, name: str) -> list["TableReader"]:
        rows = self.get(name, list)
        return [_row(row, f"{self.key(name)}[{i}]") for i, row in enumerate(rows)]


def _row(row: Any, where: str) -> TableReader:
    if not isinstance(row, dict):
        raise ProfileError(f"key '{where}' must be a table")
    return TableReader(row, where)


def _kind_name(kind: type | tuple[type, ...]) -> str:
    kinds = kind if isinstance(kind, tuple) else (kind,)
    return " or ".join({"str": "a string", "float": "a number", "int": "an integer",
                        "dict": "a table", "list": "an array"}.get(k.__name__, k.__name__)
                       for k in kinds)


def positive(reader: TableReader, name: str) -> float:
    value: float = reader.get(name, float)
    if value <= 0:
        raise ProfileError(f"key '{reader.key(name)}' must be positive, got {value}")
    return value
