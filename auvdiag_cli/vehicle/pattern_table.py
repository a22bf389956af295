"""``[[pattern]]`` in a profile: the pattern table that names the component behind each
binary vector b of the mission's judged signals."""

from dataclasses import dataclass

from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError


@dataclass(frozen=True)
class PatternRow:
    case: int
    b: dict[str, int]
    components: tuple[str, ...]


def parse_pattern(rows: list[TableReader], sensor_names: list[str], components: set[str]
             ) -> tuple[PatternRow, ...]:
    """The optional pattern table; a row that repeats another's case or b vector is an
    error naming both rows."""
    pattern: list[PatternRow] = []
    for reader in rows:
        row = _pattern_row(reader, sensor_names, components)
        for earlier, other in zip(rows, pattern, strict=False):
            if other.case == row.case:
                raise ProfileError(f"key '{reader.key('case')}' repeats case {row.case} of "
                                   f"{earlier.where}")
            if other.b == row.b:
                raise ProfileError(f"key '{reader.key('b')}' repeats the b vector of "
                                   f"{earlier.where} (case {other.case})")
        pattern.append(row)
    return tuple(pattern)


def _pattern_row(reader: TableReader, sensor_names: list[str], components: set[str]
                 ) -> PatternRow:
    b_reader = reader.sub("b")
    unknown = [name for name in b_reader.names() if name not in sensor_names]
    if unknown:
        raise ProfileError(f"key '{b_reader.key(unknown[0])}' names no sensor (b has one bit "
                           f"per sensor: {', '.join(sensor_names)})")
    b = {}
    for name in sensor_names:
        bit = b_reader.get(name, int)
        if bit not in (0, 1):
            raise ProfileError(f"key '{b_reader.key(name)}' must be 0 or 1")
        b[name] = bit
    named = [str(c) for c in reader.get("components", list)]
    strangers = [c for c in named if c not in components]
    if strangers:
        raise ProfileError(f"key '{reader.key('components')}' names unknown component "
                           f"{strangers[0]!r} (the profile's: {', '.join(sorted(components))})")
    return PatternRow(reader.get("case", int), b, tuple(named))
