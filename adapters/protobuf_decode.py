"""A Protocol Buffers message decoded into plain values by its type (`protobuf_schema`): a
mapping of field names, repeated fields as lists, maps as mappings, nested messages as
mappings; a field not set reads as its default, or as None (no reading) where its type says
when it was not set. Profiles reach its values by field path as in a JSON message
(`pose.position.x`, `motors[2]`, `gains["roll"]`)."""

import struct
from collections.abc import Callable, Sequence
from typing import Any

from adapters import protobuf_schema as schema
from adapters.protobuf_schema import FieldType, MessageType, SchemaError, resolve
from adapters.protobuf_wire import (
    FIXED32,
    FIXED64,
    LENGTH_DELIMITED,
    VARINT,
    WireError,
    fields,
    packed_fixed,
    packed_varints,
    signed,
    zigzag,
)

# Deeper nesting than any vehicle's message: a recursive type fed crafted bytes stops here.
MAX_DEPTH = 32
# How a fixed-size type is unpacked, and from which wire type.
_FIXED = {schema.DOUBLE: ("d", FIXED64), schema.FIXED64: ("Q", FIXED64),
          schema.SFIXED64: ("q", FIXED64), schema.FLOAT: ("f", FIXED32),
          schema.FIXED32: ("I", FIXED32), schema.SFIXED32: ("i", FIXED32)}
_VARINT: dict[int, Callable[[int], Any]] = {
    schema.INT64: signed, schema.UINT64: int, schema.INT32: lambda v: signed(v, 32),
    schema.UINT32: lambda v: v & 0xFFFFFFFF, schema.BOOL: bool,
    schema.ENUM: lambda v: signed(v, 32), schema.SINT32: lambda v: zigzag(v & 0xFFFFFFFF),
    schema.SINT64: zigzag}
_DEFAULTS: dict[int, Any] = {schema.STRING: "", schema.BYTES: b"", schema.BOOL: False,
                             schema.DOUBLE: 0.0, schema.FLOAT: 0.0}


# The fields to decode, by number, each with the fields of its own message to decode (None:
# all of them): a log's messages carry far more than a profile reads.
Wanted = dict[int, "Wanted | None"]


def decoder(types: dict[str, MessageType], type_name: str,
            paths: Sequence[str] | None = None) -> Callable[[bytes], Any]:
    """Decodes one message of ``type_name`` (SchemaError where the types lack it); with
    ``paths``, only the fields on them (every field where one of them is not in the type, so
    that what it lacks can be told with what it has)."""
    message_type = resolve(types, type_name)
    _check_reachable(types, message_type)
    wanted = None if paths is None else wanted_fields(types, message_type, paths)
    return lambda data: decode(types, message_type, data, 0, wanted)


def wanted_fields(types: dict[str, MessageType], root: MessageType,
                  paths: Sequence[str]) -> Wanted | None:
    """The fields ``paths`` reach in ``root`` (None where one of them is not there)."""
    from adapters.fieldpath import parse_field_path

    tree: Wanted = {}
    for path in paths:
        node: Wanted | None = tree
        message_type, steps = root, list(parse_field_path(path))
        while steps and node is not None:
            step = steps.pop(0)
            field = next((f for f in message_type.fields.values() if f.name == step), None)
            if field is None:
                return None
            if field.repeated and steps:
                steps.pop(0)                  # the element's index, or the map entry's key
            inner = types.get(field.type_name) if field.kind == schema.MESSAGE else None
            if inner is None or inner.map_entry or not steps:
                node[field.number] = None     # the whole field
                break
            node = node.setdefault(field.number, {})
            message_type = inner
    return tree


def _check_reachable(types: dict[str, MessageType], root: MessageType) -> None:
    """Every message type ``root`` may hold resolves (SchemaError before any message is
    read, not in the middle of the log)."""
    seen, waiting = {root.name}, [root]
    while waiting:
        for field in waiting.pop().fields.values():
            if field.kind == schema.MESSAGE:
                inner = resolve(types, field.type_name)
                if inner.name not in seen:
                    seen.add(inner.name)
                    waiting.append(inner)


def decode(types: dict[str, MessageType], message_type: MessageType, data: bytes,
           depth: int, wanted: Wanted | None = None) -> dict[str, Any]:
    """The message's fields (only those ``wanted``, where given)."""
    if depth > MAX_DEPTH:
        raise WireError(f"messages nested deeper than {MAX_DEPTH}")
    values: dict[str, Any] = {}
    for number, wire, raw in fields(data, wanted):
        field = message_type.fields.get(number)
        if field is None:
            continue                    # a field this schema does not know: skipped
        inner = None if wanted is None else wanted[number]
        if field.repeated:
            values.setdefault(field.name, []).extend(
                _repeated(types, field, wire, raw, depth, inner))
        else:
            values[field.name] = _value(types, field, wire, raw, depth, inner)
    kept = message_type.fields.values() if wanted is None else [
        message_type.fields[number] for number in wanted]
    return {field.name: _read(types, field, values) for field in kept}


def _read(types: dict[str, MessageType], field: FieldType, values: dict[str, Any]) -> Any:
    """A field's value as read (its default, or None, where it was not set; a map's entries
    as a mapping)."""
    if field.name not in values:
        return _unset(field)
    value = values[field.name]
    if field.repeated and field.kind == schema.MESSAGE \
            and resolve(types, field.type_name).map_entry:
        return {entry.get("key"): entry.get("value") for entry in value}
    return value


def _unset(field: FieldType) -> Any:
    if field.repeated:
        return []
    if field.presence or field.kind == schema.MESSAGE:
        return None
    return _DEFAULTS.get(field.kind, 0)


def _repeated(types: dict[str, MessageType], field: FieldType, wire: int,
              raw: int | bytes, depth: int, wanted: Wanted | None) -> list[Any]:
    """One occurrence of a repeated field: a value, or a packed run of scalars."""
    packable = field.kind not in (schema.STRING, schema.BYTES, schema.MESSAGE)
    if not (packable and wire == LENGTH_DELIMITED):
        return [_value(types, field, wire, raw, depth, wanted)]
    assert isinstance(raw, bytes)
    if field.kind in _FIXED:
        return list(packed_fixed(raw, _FIXED[field.kind][0]))
    return [_VARINT[field.kind](v) for v in packed_varints(raw)]


def _value(types: dict[str, MessageType], field: FieldType, wire: int, raw: int | bytes,
           depth: int, wanted: Wanted | None) -> Any:
    kind = field.kind
    if kind in _VARINT and wire == VARINT:
        assert isinstance(raw, int)
        return _VARINT[kind](raw)
    if kind in _FIXED and wire == _FIXED[kind][1]:
        assert isinstance(raw, bytes)
        return struct.unpack(f"<{_FIXED[kind][0]}", raw)[0]
    if wire == LENGTH_DELIMITED and kind in (schema.STRING, schema.BYTES, schema.MESSAGE):
        assert isinstance(raw, bytes)
        if kind == schema.STRING:
            return raw.decode("utf-8", errors="replace")
        if kind == schema.BYTES:
            return raw
        return decode(types, resolve(types, field.type_name), raw, depth + 1, wanted)
    raise WireError(f"field {field.name!r} (number {field.number}) arrives with wire type "
                    f"{wire}, which its type does not use")


def field_paths(types: dict[str, MessageType], type_name: str, prefix: str = "",
                depth: int = 0) -> list[str]:
    """Every value's path in a message type: ``pose.position.x``, ``motors[0]`` (a repeated
    field shown by its first element); maps, whose keys only messages tell, are left out."""
    from adapters.fieldnames import MAX_DEPTH as LISTED_DEPTH
    from adapters.fieldpath import join_step

    try:
        message_type = resolve(types, type_name)
    except SchemaError:
        return []
    paths: list[str] = []
    for field in message_type.fields.values():
        path = join_step(prefix, field.name) + ("[0]" if field.repeated else "")
        if field.kind != schema.MESSAGE:
            paths.append(path)
            continue
        inner = types.get(field.type_name)
        if inner is not None and not inner.map_entry and depth < LISTED_DEPTH:
            paths += field_paths(types, field.type_name, path, depth + 1)
    return paths
