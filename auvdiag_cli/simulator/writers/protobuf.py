"""ROS messages as Protocol Buffers, the way a vehicle without ROS logs its state to MCAP
(Foxglove's tools, many autopilots' companion software): each ROS type a proto3 message of
the same fields in the same order (`pkg/msg/Name` -> `pkg.Name`), a channel's schema the
FileDescriptorSet of its type and every type it holds, each message in the wire format.

Both are written here by hand (no protobuf runtime is a dependency); the tests check that
the protobuf library reads them."""

import struct
from collections.abc import Iterator
from typing import Any

import numpy as np

_VARINT, _FIXED64, _LENGTH, _FIXED32 = 0, 1, 2, 5
# ROS base type -> (FieldDescriptorProto.Type, how it is written)
_BASE = {"float64": (1, "d"), "float32": (2, "f"), "int64": (3, "v"), "uint64": (4, "v"),
         "int32": (5, "v"), "int16": (5, "v"), "int8": (5, "v"), "uint32": (13, "v"),
         "uint16": (13, "v"), "uint8": (13, "v"), "byte": (13, "v"), "char": (13, "v"),
         "bool": (8, "v"), "string": (9, "s")}
_MESSAGE, _BYTES, _OPTIONAL, _REPEATED = 11, 12, 1, 3
# ROS arrays of bytes (an image's pixels) are one `bytes` field, not a number each.
_OCTETS = ("uint8", "byte", "char")


def varint(value: int) -> bytes:
    value &= (1 << 64) - 1          # a negative integer as ten bytes of two's complement
    out = bytearray()
    while value >= 0x80:
        out.append(value & 0x7F | 0x80)
        value >>= 7
    out.append(value)
    return bytes(out)


def _key(number: int, wire: int) -> bytes:
    return varint(number << 3 | wire)


def _delimited(number: int, payload: bytes) -> bytes:
    return _key(number, _LENGTH) + varint(len(payload)) + payload


def proto_name(msgtype: str) -> str:
    """``pkg/msg/Name`` -> ``pkg.Name``."""
    parts = msgtype.split("/")
    return f"{parts[0]}.{parts[-1]}"


class ProtobufTypes:
    """The proto3 shape of ROS types of a rosbags type store, and their messages encoded."""

    def __init__(self, store: Any) -> None:
        from rosbags.typesys.base import normalize_fieldname

        self.store = store
        self.name = normalize_fieldname
        self.shapes: dict[str, list[tuple[int, str, str, Any, bool]]] = {}

    def _fields(self, msgtype: str) -> list[tuple[int, str, str, Any, bool]]:
        """(number, name, ROS kind, detail, repeated) of each field of ``msgtype`` (worked
        out once a type: every message of it is encoded by them)."""
        if msgtype not in self.shapes:
            shape = []
            for number, (name, (node, detail)) in enumerate(self.store.fielddefs[msgtype][1], 1):
                kind, repeated = node.name, kind_repeats(node.name)
                if repeated:
                    (element_node, detail), _ = detail
                    kind = element_node.name
                shape.append((number, self.name(name), kind, detail, repeated))
            self.shapes[msgtype] = shape
        return self.shapes[msgtype]

    def descriptor_set(self, msgtype: str) -> bytes:
        """The serialised FileDescriptorSet of ``msgtype`` and every type it holds, one file
        per ROS package, each file after those it depends on."""
        order: list[str] = []
        self._collect(msgtype, order)
        packages: dict[str, list[str]] = {}
        for held in order:
            packages.setdefault(proto_name(held).split(".")[0], []).append(held)
        files = b""
        for package, types in packages.items():
            needs = {proto_name(inner).split(".")[0] for held in types
                     for *_, inner in self._nested(held)} - {package}
            body = _delimited(1, f"{package}.proto".encode()) + _delimited(2, package.encode())
            body += b"".join(_delimited(3, f"{n}.proto".encode()) for n in sorted(needs))
            body += b"".join(_delimited(4, self._descriptor(held)) for held in types)
            files += _delimited(1, body + _delimited(12, b"proto3"))
        return files

    def _nested(self, msgtype: str) -> Iterator[tuple[int, str]]:
        for number, _, kind, detail, _ in self._fields(msgtype):
            if kind == "NAME":
                yield number, detail

    def _collect(self, msgtype: str, order: list[str]) -> None:
        """``order``: the types ``msgtype`` holds, depth first, then itself."""
        for _, inner in self._nested(msgtype):
            if inner not in order:
                self._collect(inner, order)
        if msgtype not in order:
            order.append(msgtype)

    def _descriptor(self, msgtype: str) -> bytes:
        body = _delimited(1, proto_name(msgtype).split(".")[1].encode())
        for number, name, kind, detail, repeated in self._fields(msgtype):
            octets = repeated and kind == "BASE" and detail[0] in _OCTETS
            field = _delimited(1, name.encode()) + _key(3, _VARINT) + varint(number)
            field += _key(4, _VARINT) + varint(_REPEATED if repeated and not octets
                                               else _OPTIONAL)
            if kind == "NAME":
                field += _key(5, _VARINT) + varint(_MESSAGE)
                field += _delimited(6, f".{proto_name(detail)}".encode())
            else:
                field += _key(5, _VARINT) + varint(_BYTES if octets else _BASE[detail[0]][0])
            body += _delimited(2, field)
        return body

    def encode(self, message: Any, msgtype: str) -> bytes:
        """``message`` (a rosbags message of ``msgtype``) in the wire format: numbers that
        repeat packed, values equal to their default left out, as proto3 writes them."""
        out = b""
        for number, name, kind, detail, repeated in self._fields(msgtype):
            value = getattr(message, name)
            if kind == "NAME":
                items = list(value) if repeated else [value]
                out += b"".join(_delimited(number, self.encode(item, detail)) for item in items)
            elif repeated and detail[0] in _OCTETS:
                out += _delimited(number, bytes(np.asarray(value, np.uint8))) if len(value) \
                    else b""
            elif repeated:
                out += _repeated(number, _BASE[detail[0]][1], value)
            else:
                out += _scalar(number, _BASE[detail[0]][1], value)
        return out


def kind_repeats(node_name: str) -> bool:
    return node_name in ("ARRAY", "SEQUENCE")


def _scalar(number: int, how: str, value: Any) -> bytes:
    if isinstance(value, np.generic):
        value = value.item()
    if not value:
        return b""
    if how == "s":
        return _delimited(number, str(value).encode())
    if how == "v":
        return _key(number, _VARINT) + varint(int(value))
    wire = _FIXED64 if how == "d" else _FIXED32
    return _key(number, wire) + struct.pack(f"<{how}", value)


def _repeated(number: int, how: str, values: Any) -> bytes:
    items = [v.item() if isinstance(v, np.generic) else v for v in values]
    if not items:
        return b""
    if how == "s":
        return b"".join(_delimited(number, str(v).encode()) for v in items)
    if how == "v":
        return _delimited(number, b"".join(varint(int(v)) for v in items))
    return _delimited(number, struct.pack(f"<{len(items)}{how}", *items))
