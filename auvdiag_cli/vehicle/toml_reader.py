"""Typed access to parsed TOML tables, with every error naming the full key."""

from typing import Any

from auvdiag_errors import ProfileError


class _KeysRead:
    """Every table read from one document, by its dotted location, and the keys asked of it:
    a key no part of the parser asked for is unknown (a typo would otherwise be lost)."""

    def __init__(self) -> None:
        self.tables: dict[str, dict[str, Any]] = {}
        self.asked: dict[str, set[str]] = {}

    def add(self, where: str, table: dict[str, Any]) -> None:
        self.tables[where] = table
        self.asked.setdefault(where, set())


class TableReader:
    """A TOML table and its dotted location, for errors that name the key."""

    def __init__(self, table: dict[str, Any], where: str, read: _KeysRead | None = None
                 ) -> None:
        self.table = table
        self.where = where
        self._read = _KeysRead() if read is None else read
        self._read.add(where, table)

    def key(self, name: str) -> str:
        return f"{self.where}.{name}" if self.where else name

    def get(self, name: str, kind: type | tuple[type, ...], default: Any = ...) -> Any:
        self._read.asked[self.where].add(name)
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
        return TableReader(self.get(name, dict), self.key(name), self._read)

    def items(self, name: str) -> list["TableReader"]:
        rows = self.get(name, list)
        return [self._row(row, f"{self.key(name)}[{i}]") for i, row in enumerate(rows)]

    def _row(self, row: Any, where: str) -> "TableReader":
        if not isinstance(row, dict):
            raise ProfileError(f"key '{where}' must be a table")
        return TableReader(row, where, self._read)

    def names(self) -> list[str]:
        """The table's keys, each one taken as read: a table of names the user chooses
        (modes, sources, a mix)."""
        self._read.asked[self.where].update(self.table)
        return list(self.table)

    def check_all_read(self) -> None:
        """Raise for the first key of this document that no part of the parser read."""
        for where, table in self._read.tables.items():
            asked = self._read.asked[where]
            unknown = [name for name in table if name not in asked]
            if unknown:
                place = f"{where}.{unknown[0]}" if where else unknown[0]
                raise ProfileError(f"unknown key '{place}' (a typo? "
                                   + (f"'{where}' takes: {', '.join(sorted(asked))})" if where
                                      else f"the profile's tables: {', '.join(sorted(asked))})"))


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
