"""How one signal's values are picked from its topic's messages, message by message or a
column at a time (`collect.SignalCollector` keeps one per signal)."""

import operator
from collections.abc import Callable, Sequence
from functools import cached_property, partial
from typing import Any

import numpy as np

from adapters.fieldpath import field_getter, resolves
from adapters.signals import FieldSource, as_text, euler_angle

# Fields that tell a sensor's instances apart (DataFlash IMU, BARO, GPS... carry one; a
# ULog topic's multi id is read as `instance`).
INSTANCE_FIELDS = ("I", "Instance", "instance")
# The instance a message without an instance field is (ArduPilot before 4.1 logged its first
# IMU, BARO, MAG as IMU, BARO, MAG with no `I` field and the others as IMU2, IMU3...): a
# `where` asking for this instance reads such messages whole.
FIRST_INSTANCE = "0"
# A topic's messages as columns: field path → one value per message.
ColumnSource = Callable[[str], np.ndarray]


class Extractor:
    """One signal's field read from its topic's messages: the message filters its source's
    `where` sets, and the sensor instances a column mixes."""

    def __init__(self, name: str, source: FieldSource) -> None:
        self.name, self.source = name, source

    # Made at the first message read whole: a CSV column is a name, not a path.
    @cached_property
    def get(self) -> Callable[[Any], Any]:
        if not self.source.angle:
            return field_getter(self.source.field)
        parts = [field_getter(path) for path in self.source.quaternion]
        angle = self.source.angle
        return lambda message: euler_angle(angle, *(float(get(message)) for get in parts))

    def column(self, columns: ColumnSource) -> np.ndarray:
        """Its raw values, every message at once."""
        if not self.source.angle:
            return columns(self.source.field)
        parts = [np.asarray(columns(path), np.float64) for path in self.source.quaternion]
        return np.asarray(euler_angle(self.source.angle, *parts))

    @cached_property
    def where(self) -> list[tuple[str, Callable[[Any], Any], str]]:
        return [(key, field_getter(key), value) for key, value in self.source.where]

    def matches(self, message: Any) -> bool:
        return all(as_text(get(message)) == value for key, get, value in self.where
                   if not _before_instances(key, value, partial(resolves, message, key)))

    def filters(self, fields: Sequence[str]) -> list[tuple[str, str]]:
        """The `where` conditions messages with these fields are filtered on: none on an
        instance field they lack when the first instance is wanted (`FIRST_INSTANCE`)."""
        return [(key, value) for key, value in self.source.where
                if not _before_instances(key, value, partial(operator.contains, fields, key))]

    def rows_matching(self, column: ColumnSource, rows: int, fields: Sequence[str]
                      ) -> np.ndarray:
        """The `where` filter on columns: each distinct value is compared once."""
        keep = np.ones(rows, bool)
        for key, value in self.filters(fields):
            distinct, which = np.unique(column(key), return_inverse=True)
            keep &= np.array([as_text(d) == value for d in distinct.tolist()], bool)[which]
        return keep

    def mixed_instances(self, column: ColumnSource, fields: Sequence[str], keep: Any
                        ) -> tuple[str, list[str]] | None:
        """The instance field and its values when the kept rows mix several instances of
        one sensor (and the profile neither chose one nor asked for a merge)."""
        chosen = {key for key, _ in self.source.where}
        for key in INSTANCE_FIELDS:
            if key in fields and key not in chosen and not self.source.merge_instances:
                values = np.unique(column(key)[keep])
                if values.size > 1:
                    return key, [as_text(v) for v in values.tolist()]
        return None


def _before_instances(key: str, value: str, present: Callable[[], bool]) -> bool:
    """A `where` on the first instance of a sensor, on a message from before instance
    fields: it is that instance. ``present`` (whether the message has the field) is asked
    only then: on the per-message path it costs a field lookup a message."""
    return key in INSTANCE_FIELDS and value == FIRST_INSTANCE and not present()


