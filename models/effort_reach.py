"""Where a weak member of an effort group moves the shares, when its mixer cannot drive it
alone.

A controller makes up for a weak actuator through its mixer: the extra effort it asks for
lies in the mixer's reach (the span of its columns over the efforts the controller holds).
Where that reach is every direction of the group (a quadrotor's four rotors, mixed from
thrust, roll, pitch and yaw), the weak member alone is driven harder and its signature is
its own share up and the others' down alike (`models.effort.weakness_directions`). Where
it is not (a vectored ROV's four horizontal thrusters, mixed from surge, sway and yaw: three
efforts for four thrusters), the lost thrust f·u_k along e_k comes back as P·e_k, P the
projection on the reach: a weak thruster k raises the command of j by about
f·u_k·P_jk, and its effort |u_j| by that times the sign of u_j. Under way on the BlueROV2
that is its own share up and its fore-and-aft partner's down by as much, the other two
near normal: far from "the others down alike".

The signature of a span is those rises summed over its steps, less each member's share of
their mean (the shares average to one), in units of each member's spread; it depends on
which way each thruster pushed, so it is taken from the span's own commands. It names the
weak member (`engine.effort_naming.signature_matches`). The whole-log test judges along
the plain signatures; the test against the log's own beginning judges a group the mixer
cannot drive member by member along these, in the noise of its windows' correlated
departures (`models.effort_correlation`), over the operating condition it holds most
(`GroupSetup.change_bin`)."""

from typing import Any

import numpy as np

from models.effort import EffortGroup
from models.effort_directions import weakness_directions

REACH_TOLERANCE = 1e-9     # of the largest singular value: a direction the mix cannot drive


def as_table(rows: Any) -> tuple[tuple[float, ...], ...] | None:
    """Rows of numbers (an array, or a model file's lists) as a group keeps a square table
    (its reach, its balance); None stays None."""
    return None if rows is None else tuple(tuple(float(v) for v in row) for row in rows)


def reach(mix_rows: np.ndarray) -> np.ndarray | None:
    """(members, members) projection on the span of the mixer's columns (``mix_rows``:
    (members, efforts held), each member's factor on each effort); None where that span is
    every direction (the weak member alone is driven harder)."""
    if mix_rows.size == 0:
        return None
    basis, singular, _ = np.linalg.svd(mix_rows, full_matrices=False)
    rank = int((singular > REACH_TOLERANCE * max(float(singular.max()), 1e-300)).sum())
    if rank >= mix_rows.shape[0] or rank == 0:
        return None
    kept = basis[:, :rank]
    return np.asarray(kept @ kept.T)


def rises(commands: np.ndarray, factors: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """(members k, members j): how much member j's effort rises over these steps, per unit
    of the fraction of thrust member k lost: Σ_t u_k sign(u_j) P_jk / c_j (c: the mixing
    factors by magnitude)."""
    signs = np.where(commands < 0, -1.0, 1.0)
    return np.asarray(commands.T @ signs * projection.T / factors[None, :])


def signature_directions(rises: np.ndarray, shares: np.ndarray, sigma: np.ndarray
                         ) -> np.ndarray:
    """(members k, members j): unit directions, in units of each member's σ, in which a
    weakness of member k moves the departures of a span with these ``rises`` and ``shares``.
    The component along σ, which departures never take (the shares average to one), is
    left out."""
    scaled = (rises - shares[None, :] * rises.mean(axis=1, keepdims=True)) / sigma[None, :]
    unit_sigma = sigma / np.linalg.norm(sigma)
    scaled = scaled - np.outer(scaled @ unit_sigma, unit_sigma)
    norms = np.linalg.norm(scaled, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(np.where(norms > 0, scaled / norms, 0.0))


def balance(tilt_rows: np.ndarray) -> np.ndarray | None:
    """(members k, members j): how the controller's balance of the tilting moments moves
    member j's effort where member k falls short (``tilt_rows``: each member's roll and pitch
    factors): j's lever against k's, so that the member across from k (a quadrotor's
    diagonal partner) is eased as k is pushed; None where the members tilt nothing."""
    table = tilt_rows @ tilt_rows.T
    return None if not np.any(table) else np.asarray(table, float)


# Where a weak member's signature may lie between its plain one and the tilt balance's:
# as many directions between the two as this (a rotor that still gives most of what it is
# asked for moves the shares along the first; one that has stopped, pushed to its limit
# while the member across is eased to keep the vehicle level, along the second).
BALANCE_STEPS = 11


def named_signatures(group: EffortGroup, commands: np.ndarray, shares: np.ndarray,
                     sigma: np.ndarray) -> np.ndarray:
    """(members k, candidates, members j): the signatures a log's departures (its
    ``shares``, each in units of ``sigma``) are matched with to name its weak member, the
    best of each member's candidates counting: the mixer's over the log's steady
    ``commands`` where it cannot drive the group member by member; else the plain ones,
    and where the profile's mix gives the tilt balance (`balance`), the directions from
    each plain one to the balance's."""
    projection = group.projection
    if projection is not None:
        return signature_directions(rises(commands, np.asarray(group.factors), projection),
                                    shares, sigma)[:, None, :]
    plain = weakness_directions(len(group.members))
    if group.balance is None:
        return plain[:, None, :]
    tilts = np.asarray(group.balance, float)
    tilts = tilts - tilts.mean(axis=1, keepdims=True)
    norms = np.linalg.norm(tilts, axis=1, keepdims=True)
    tilts = np.where(norms > 0, tilts / np.where(norms > 0, norms, 1.0), plain)
    steps = np.linspace(0.0, 1.0, BALANCE_STEPS)[None, :, None]
    between = (1 - steps) * plain[:, None, :] + steps * tilts[:, None, :]
    return np.asarray(between / np.linalg.norm(between, axis=2, keepdims=True))

