"""A profile's ``[sources.FAMILY]`` tables: where each signal lives in a log of that format
family, the operating flag (and its fallback), a UTC time the log carries, segment markers
and a CSV clock."""

from collections.abc import Sequence

from adapters.fieldpath import parse_field_path
from adapters.ros_words import ROS_WORD_SOURCES
from adapters.signals import (
    CLOCK_REFERENCE,
    EULER_ANGLES,
    MOOS_VALUE,
    OPERATING,
    OTHER_VALUES,
    TIME_UNITS,
    FieldSource,
    LogSources,
    SegmentSource,
    TimeColumn,
)
from auvdiag_cli.vehicle.toml_reader import TableReader
from auvdiag_errors import ProfileError


def _topic(reader: TableReader) -> str:
    """`topic` (ROS, MCAP), `message` (MAVLink, DataFlash) and `variable` (MOOS) are the
    same key; a CSV `column` is its own topic."""
    if "column" in reader.table:
        return str(reader.get("column", str))
    if "variable" in reader.table:
        return str(reader.get("variable", str))
    if "topic" not in reader.table and "message" in reader.table:
        return str(reader.get("message", str))
    return str(reader.get("topic", str))


def _field(reader: TableReader) -> str:
    """A CSV `column` is a name, whatever it holds ("depth (m)"); any other source's
    `field` a path into its message (`twist.linear.x`, `channels[2]`), checked here; an
    angle's, its quaternion's w."""
    if "quaternion" in reader.table:
        return _quaternion(reader)[0][0]
    if "column" in reader.table:
        return str(reader.get("column", str))
    if "variable" in reader.table:      # a MOOS variable's posting is its `value`
        return _path(reader, "field", reader.get("field", str, MOOS_VALUE))
    return _path(reader, "field", reader.get("field", str))


def _quaternion(reader: TableReader) -> tuple[tuple[str, ...], str]:
    """``quaternion = ["q[0]", "q[1]", "q[2]", "q[3]"]`` (the paths of w, x, y, z) with
    ``angle = "roll"``: an attitude angle from a logged quaternion (PX4, ROS)."""
    if "quaternion" not in reader.table:
        return (), ""
    paths = reader.get("quaternion", list)
    if len(paths) != 4 or not all(isinstance(p, str) for p in paths):
        raise ProfileError(f"key '{reader.key('quaternion')}' must list the paths of its w, "
                           f'x, y and z, e.g. ["q[0]", "q[1]", "q[2]", "q[3]"], got {paths!r}')
    angle = reader.get("angle", str)
    if angle not in EULER_ANGLES:
        raise ProfileError(f"key '{reader.key('angle')}' must be one of "
                           f"{', '.join(EULER_ANGLES)}, got {angle!r}")
    if "field" in reader.table:
        raise ProfileError(f"key '{reader.key('field')}': a quaternion's angle has no field "
                           "(its paths are in quaternion)")
    return tuple(_path(reader, "quaternion", p) for p in paths), angle


def _path(reader: TableReader, key: str, path: str) -> str:
    try:
        parse_field_path(path)
    except ValueError as error:
        raise ProfileError(f"key '{reader.key(key)}': {error}") from None
    return path


def _field_source(entry: TableReader) -> FieldSource:
    matched = entry.sub("where") if "where" in entry.table else None
    paths = "column" not in entry.table          # a CSV filters on other columns by name
    where = {} if matched is None else {_path(matched, name, name) if paths else name:
                                        matched.table[name] for name in matched.names()}
    return FieldSource(
        _topic(entry), _field(entry), entry.get("scale", float, 1.0),
        entry.get("offset", float, 0.0), tuple((k, str(v)) for k, v in where.items()),
        entry.get("merge_instances", bool, False), entry.get("bits", int, 0),
        entry.get("changes_only", bool, False), *_value_map(entry), *_quaternion(entry))


def _value_map(entry: TableReader) -> tuple[tuple[tuple[int | str, float], ...], float | None]:
    """``values = { 10 = 1, 11 = 0 }`` or ``{ DRIVE = 1, "*" = 0 }``: the raw values that
    count (integers, or texts such as a mode's name) and their meaning, and what any other
    value means (``"*"``; without it, other values are no sample)."""
    if "values" not in entry.table:
        return (), None
    table = entry.sub("values")
    listed: list[tuple[int | str, float]] = []
    for raw in table.names():
        if raw != OTHER_VALUES:
            listed.append((_integer_or_text(raw), table.get(raw, float)))
    if not listed and OTHER_VALUES not in table.table:
        raise ProfileError(f"key '{entry.key('values')}' lists no value: map raw values to "
                           'numbers, e.g. { 10 = 1, 11 = 0 } or { DRIVE = 1, "*" = 0 }')
    return tuple(listed), table.get(OTHER_VALUES, float, None)


def _integer_or_text(raw: str) -> int | str:
    """A key that reads as an integer matches that number (and its digits in a text)."""
    try:
        return int(raw)
    except ValueError:
        return raw


def _operating(reader: TableReader) -> tuple[FieldSource, FieldSource | None]:
    """``operating``: one source, or an array of two: the second read where a log has no
    message of the first."""
    if not isinstance(reader.table["operating"], list):
        return _field_source(reader.sub("operating")), None
    rows = reader.items("operating")
    if len(rows) not in (1, 2):
        raise ProfileError(f"key '{reader.key('operating')}' must be one source or an array "
                           f"of two (the second a fallback), got {len(rows)}")
    return _field_source(rows[0]), _field_source(rows[1]) if len(rows) == 2 else None


def log_sources(reader: TableReader, signal_names: list[str], optional: Sequence[str] = (),
                family: str = "") -> LogSources:
    """The family's sources of ``signal_names``; a log may lack those of ``optional``. A
    ROS log's own words (`/rosout`, mavros' status texts, `/diagnostics`) are read
    wherever it has them."""
    signals_table = reader.sub("signals")
    signals = {name: _field_source(signals_table.sub(name)) for name in signal_names}
    fallbacks = {}
    if "operating" in reader.table:   # a flag: the vehicle is operating where it is not 0
        signals[OPERATING], fallback = _operating(reader)
        fallbacks = {OPERATING: fallback} if fallback is not None else {}
    if "clock_reference" in reader.table:   # a UTC time: a log may lack it
        if CLOCK_REFERENCE in signal_names:
            raise ProfileError(f"signal name {CLOCK_REFERENCE!r} is reserved for the UTC "
                               "time a log carries ([sources.FAMILY] clock_reference)")
        signals[CLOCK_REFERENCE] = _field_source(reader.sub("clock_reference"))
        optional = (*optional, CLOCK_REFERENCE)
    segment = None
    if "segment" in reader.table:
        entry = reader.sub("segment")
        segment = SegmentSource(_topic(entry), _field(entry), entry.get("prefix", str, ""))
    time = None
    if "time" in reader.table:
        entry = reader.sub("time")
        time = TimeColumn(entry.get("column", str), entry.get("unit", str, "s").lower())
        if time.unit not in TIME_UNITS:
            raise ProfileError(f"key '{entry.key('unit')}' must be one of "
                               f"{', '.join(TIME_UNITS)}, got {time.unit!r}")
    # ROS: the namespace the topics are under ("" the root); found from the log if unset.
    namespace = reader.get("namespace", str, None)
    return LogSources(signals, segment, time, fallbacks, namespace, frozenset(optional),
                      words=ROS_WORD_SOURCES if family == "ros" else ())
