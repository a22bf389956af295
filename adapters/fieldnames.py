"""The field paths a message offers, for messages that tell a user what to write in a profile:
`inspect` lists them, and a field that does not resolve names the ones that would."""

import difflib
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from adapters.fieldpath import join_step

# How deep nested ROS messages are listed, and how many entries a message shows.
MAX_DEPTH = 4
MAX_LISTED = 12


def closest_first(wanted: str, names: Iterable[str], limit: int = MAX_LISTED) -> list[str]:
    """``names`` ordered by likeness to ``wanted`` (the likeliest typo fix first)."""
    unique = list(dict.fromkeys(names))
    likeness = {name: difflib.SequenceMatcher(None, wanted.lower(), name.lower()).ratio()
                for name in unique}
    return sorted(unique, key=lambda name: -likeness[name])[:limit]


def unresolved(topic: str, path: str, signal: str, names: Sequence[str]) -> str:
    """The problem text for a field path that a topic's messages do not have."""
    offered = ", ".join(closest_first(path, names)) if names else "none known"
    return f"{topic} has no field {path!r} (signal {signal}); its fields, closest first: {offered}"


def message_fields(typestore: Any, msgtype: str) -> list[tuple[str, Any]]:
    """A ROS message type's fields (name, rosbags' descriptor), from the store's definitions:
    its ``get_msgdef`` would also compile a dozen (de)serialisers per type, unused here.
    KeyError for a type the store does not know."""
    from rosbags.typesys.base import normalize_fieldname

    return [(normalize_fieldname(name), desc) for name, desc in typestore.fielddefs[msgtype][1]]


def ros_field_paths(typestore: Any, msgtype: str, prefix: str = "", depth: int = 0
                    ) -> list[str]:
    """Every value's path in a ROS message definition: ``twist.linear.x``, ``data[0]``
    (a sequence or array is shown by its first element)."""
    paths: list[str] = []
    try:
        fields = message_fields(typestore, msgtype)
    except Exception:  # a type the store does not know: nothing to list
        return paths
    for name, (kind, detail) in fields:
        path = f"{prefix}{name}"
        kind_name = kind.name
        if kind_name in ("ARRAY", "SEQUENCE"):
            element_kind, element = detail[0]
            path += "[0]"
            kind_name, detail = element_kind.name, element
        if kind_name == "NAME" and depth < MAX_DEPTH:
            paths += ros_field_paths(typestore, detail, f"{path}.", depth + 1)
        elif kind_name == "BASE":
            paths.append(path)
    return paths


def object_field_paths(message: Any, prefix: str = "", depth: int = 0) -> list[str]:
    """Paths of a decoded message object (dataclass-like or a mapping); a key that is not a
    plain name quoted (`adapters.fieldpath.join_step`)."""
    if isinstance(message, dict):
        items = list(message.items())
    elif hasattr(message, "__dataclass_fields__"):
        items = [(name, getattr(message, name)) for name in message.__dataclass_fields__]
    elif hasattr(message, "__slots__"):
        items = [(name, getattr(message, name, None)) for name in message.__slots__]
    else:
        return [prefix] if prefix else []
    paths: list[str] = []
    for name, value in items:
        if str(name).startswith("_"):
            continue
        path = join_step(prefix, str(name))
        if isinstance(value, list | tuple | np.ndarray) and len(value):
            path, value = f"{path}[0]", value[0]
        if depth < MAX_DEPTH and (isinstance(value, dict) or hasattr(value, "__dataclass_fields__")
                                  or hasattr(value, "__slots__")):
            paths += object_field_paths(value, path, depth + 1)
        else:
            paths.append(path)
    return paths


def json_schema_paths(schema: Any, prefix: str = "", depth: int = 0) -> list[str]:
    """Every value's path in a JSON Schema of an object (an MCAP channel's ``jsonschema``):
    its properties, nested objects followed, an array shown by its first item."""
    if not isinstance(schema, dict):
        return []
    while schema.get("type") == "array" and isinstance(schema.get("items"), dict):
        prefix, schema = f"{prefix}[0]", schema["items"]
    properties = schema.get("properties")
    if not isinstance(properties, dict) or depth >= MAX_DEPTH:
        return [prefix] if prefix else []
    paths: list[str] = []
    for name, inner in properties.items():
        paths += json_schema_paths(inner, join_step(prefix, str(name)), depth + 1)
    return paths
