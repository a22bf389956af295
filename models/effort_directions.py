"""The directions in which one weak member of an effort group moves the group's departures,
each in units of its member's spread: for naming the member (unit directions) and for
judging a departure along them (scaled so that Student's t holds)."""

import math

import numpy as np


def weakness_directions(members: int) -> np.ndarray:
    """(members, members): row i, the unit direction in which member i's weakness moves the
    group's departures: its own share up, the others' down alike (they average to one)."""
    if members < 2:
        return np.eye(members)
    directions = np.eye(members) - 1.0 / members
    return np.asarray(directions / np.linalg.norm(directions, axis=1, keepdims=True))


def judged_directions(members: int) -> np.ndarray:
    """`weakness_directions` scaled for judging: a group's departures sum to zero (its shares
    average to one), so members' z, each of unit variance, are correlated −1/(m − 1), and
    their projection on a unit direction across them varies m/(m − 1) times as much (a pair:
    twice; four rotors: 4/3). Scaled by √((m − 1)/m), the projection is again of unit
    variance, and Student's t keeps the false-alarm budget it promises."""
    scale = math.sqrt((members - 1) / members) if members > 1 else 1.0
    return weakness_directions(members) * scale
