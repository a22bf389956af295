"""Protocol Buffers message types as an MCAP schema of encoding "protobuf" gives them: a
FileDescriptorSet (itself a Protocol Buffers message, `google/protobuf/descriptor.proto`),
read here with the wire decoder, so that no protobuf runtime is needed to read a log.

Only what decoding needs is kept of each type: its fields' numbers, names, types, whether
they repeat, whether they say when they were not set (proto2 `optional`, proto3 `optional`,
a `oneof`), and which nested types are map entries."""

from dataclasses import dataclass

from adapters.protobuf_wire import LENGTH_DELIMITED, VARINT, WireError, fields

# FieldDescriptorProto.Type
DOUBLE, FLOAT, INT64, UINT64, INT32, FIXED64, FIXED32, BOOL, STRING, GROUP, MESSAGE, BYTES, \
    UINT32, ENUM, SFIXED32, SFIXED64, SINT32, SINT64 = range(1, 19)
_LABEL_OPTIONAL, _LABEL_REPEATED = 1, 3


@dataclass(frozen=True)
class FieldType:
    name: str
    number: int
    kind: int                 # FieldDescriptorProto.Type
    repeated: bool
    type_name: str            # a message or enum type's full name, without the leading dot
    presence: bool            # unset reads as None (no reading), not as its default


@dataclass(frozen=True)
class MessageType:
    name: str                               # full name: package.Outer.Inner
    fields: dict[int, FieldType]
    map_entry: bool = False                 # a map's entry (key = 1, value = 2)


class SchemaError(ValueError):
    """A schema that does not describe the channel's messages."""


def message_types(descriptor_set: bytes) -> dict[str, MessageType]:
    """Every message type of a serialised FileDescriptorSet, by full name."""
    types: dict[str, MessageType] = {}
    try:
        for number, wire, file in fields(descriptor_set):
            if number == 1 and wire == LENGTH_DELIMITED:
                assert isinstance(file, bytes)
                _file_types(file, types)
    except WireError as error:
        raise SchemaError(f"its FileDescriptorSet cannot be read ({error})") from None
    return types


def _file_types(file: bytes, types: dict[str, MessageType]) -> None:
    parts = _delimited_fields(file)
    package, proto3 = _text_of(parts, 2), _text_of(parts, 12) == "proto3"
    for message in parts.get(4, []):
        _message_types(message, package, proto3, types)


def _message_types(message: bytes, scope: str, proto3: bool,
                   types: dict[str, MessageType]) -> None:
    parts = _delimited_fields(message)
    name = _text_of(parts, 1)
    map_entry = any(n == 7 and w == VARINT and v
                    for options in parts.get(7, []) for n, w, v in fields(options))
    full = f"{scope}.{name}" if scope else name
    parsed = [_field(field, proto3) for field in parts.get(2, [])]
    types[full] = MessageType(full, {f.number: f for f in parsed}, map_entry)
    for inner in parts.get(3, []):
        _message_types(inner, full, proto3, types)


def _delimited_fields(message: bytes) -> dict[int, list[bytes]]:
    """A message's length-delimited fields (strings, messages) by number, in order."""
    parts: dict[int, list[bytes]] = {}
    for number, wire, value in fields(message):
        if wire == LENGTH_DELIMITED:
            assert isinstance(value, bytes)
            parts.setdefault(number, []).append(value)
    return parts


def _text_of(parts: dict[int, list[bytes]], number: int) -> str:
    """A string field's value (the last given wins, as in the wire format)."""
    return _text(parts[number][-1]) if number in parts else ""


def _field(field: bytes, proto3: bool) -> FieldType:
    name, number, label, kind, type_name = "", 0, _LABEL_OPTIONAL, 0, ""
    in_oneof = proto3_optional = False
    for key, wire, value in fields(field):
        if wire == LENGTH_DELIMITED:
            assert isinstance(value, bytes)
            if key == 1:
                name = _text(value)
            elif key == 6:
                type_name = _text(value).lstrip(".")
        elif wire == VARINT:
            assert isinstance(value, int)
            if key == 3:
                number = value
            elif key == 4:
                label = value
            elif key == 5:
                kind = value
            elif key == 9:
                in_oneof = True
            elif key == 17:
                proto3_optional = bool(value)
    if not name or not 0 < number < 1 << 29 or not DOUBLE <= kind <= SINT64:
        raise WireError(f"a field {name!r} numbered {number} of type {kind}")
    repeated = label == _LABEL_REPEATED
    presence = not repeated and (in_oneof or proto3_optional or not proto3)
    return FieldType(name, number, kind, repeated, type_name, presence)


def _text(value: bytes) -> str:
    return value.decode("utf-8", errors="replace")


def resolve(types: dict[str, MessageType], type_name: str) -> MessageType:
    """The message type ``type_name`` names (a full name; a bare name where it is unique)."""
    found = types.get(type_name)
    if found is None:
        matches = [t for name, t in types.items() if name.endswith(f".{type_name}")]
        if len(matches) != 1:
            raise SchemaError(f"its FileDescriptorSet has no message type {type_name!r}")
        found = matches[0]
    return found
