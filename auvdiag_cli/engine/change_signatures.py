"""A part's signature in the change test: the direction in which its weakening moves the
residuals of several signals at once.

A part that gives less than it should (an engine that lost its thrust, a thruster that
lost its power) moves everything it drives the same way: on a fixed-wing aircraft under
its autopilot, an engine that stops pushing leaves the aircraft lower in forward
acceleration, speed and climb than the predictor a moment ahead expects, and its
autopilot pitching down to hold its airspeed. Each signal alone may move by only a spread
or so; their signed sum moves by twice that, and one that moves the other way (a surface
that sticks nose up) is no evidence for it. A profile declares it per actuator
(`weakened = { climb = -1, ... }`: +1 where the signal reads above the prediction, -1
below), and the test judges the projection of the window z on it as one more signal,
named "<part> weakened", one-sided, with its own thresholds from calibrate.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from auvdiag_cli.vehicle.actuators import Actuator
from auvdiag_cli.vehicle.profile import Sensor

SUFFIX = " weakened"
MIN_MEMBERS = 2             # one judged signal alone is already judged as itself


@dataclass(frozen=True)
class Signature:
    """One part's signature over the judged signals: column -> sign."""

    name: str                     # "<part> weakened": the statistic's signal name
    part: str
    signs: Mapping[int, float]

    def project(self, z: np.ndarray) -> np.ndarray:
        """The window z projected on the signature (NaN where a member has none)."""
        columns = list(self.signs)
        signs = np.array([self.signs[c] for c in columns])
        return np.asarray(z[:, columns] @ signs / np.sqrt(len(columns)))


def signatures(actuators: Sequence[Actuator], judged: Sequence[str]) -> list[Signature]:
    """The signatures whose judged members (columns of ``judged``) are enough to judge."""
    found = []
    for actuator in actuators:
        signs = {judged.index(name): sign for name, sign in actuator.weakened
                 if name in judged}
        if len(signs) >= MIN_MEMBERS:
            found.append(Signature(actuator.name + SUFFIX, actuator.name, signs))
    return found


def signature_parts(names: Sequence[str], actuators: Sequence[Actuator]) -> dict[str, str]:
    """Of ``names``, each that is a signature's signal -> its part."""
    parts = {a.name + SUFFIX: a.name for a in actuators if a.weakened}
    return {name: parts[name] for name in names if name in parts}


def signature_names(actuators: Sequence[Actuator], judged: Sequence[str]) -> list[str]:
    return [s.name for s in signatures(actuators, judged)]


def signature_only(sensors: Sequence[Sensor]) -> frozenset[str]:
    """The sensors judged only within a part's signature, never alone (`signature_only`)."""
    return frozenset(s.name for s in sensors if s.signature_only)


def below_only(sensors: Sequence[Sensor]) -> frozenset[str]:
    """The sensors the change test judges only below the prediction (`below_only`)."""
    return frozenset(s.name for s in sensors if s.below_only)


def judged_within(actuators: Sequence[Actuator], sensors: Sequence[Sensor],
                  judged: Sequence[str]) -> dict[str, tuple[tuple[str, ...], str]]:
    """Each of the ``judged`` sensors judged only within signatures -> (those signatures,
    the profile's reason)."""
    found = signatures(actuators, list(judged))
    return {s.name: (tuple(f.name for f in found if judged.index(s.name) in f.signs),
                     s.signature_only)
            for s in sensors if s.signature_only and s.name in judged}


def thresholded(actuators: Sequence[Actuator], sensors: Sequence[Sensor],
                judged: Sequence[str]) -> list[str]:
    """What the test sets thresholds on and alarms by: each of the ``judged`` signals the
    profile lets stand alone, then the signatures over all of them."""
    alone = signature_only(sensors)
    return [*(name for name in judged if name not in alone),
            *signature_names(actuators, judged)]


def with_signatures(z: np.ndarray, found: Sequence[Signature]
                    ) -> tuple[np.ndarray, np.ndarray]:
    """z with a column per signature, and which columns count one way only (a signature:
    a move against it is no evidence)."""
    if not found:
        return z, np.zeros(z.shape[1], bool)
    extra = np.column_stack([s.project(z) for s in found])
    one_sided = np.r_[np.zeros(z.shape[1], bool), np.ones(len(found), bool)]
    return np.hstack([z, extra]), one_sided

