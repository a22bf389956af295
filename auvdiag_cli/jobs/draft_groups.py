"""The `[[effort]]` groups a draft proposes where the log does not say which actuators
share a job (an ArduPilot log's parameters do: `autopilot_outputs`): commands at like
levels that move together."""

from collections.abc import Sequence

import numpy as np

from auvdiag_cli.jobs.draft_text import NEUTRAL, Proposal, is_set_point

ALIKE_LEVELS = 2.0        # commands act alike when their levels lie within this factor
ALIKE_CORRELATION = 0.3   # ... and they move together (or against each other) this much


def effort_groups(commands: list[Proposal], identical: set[frozenset[str]],
                  values: Sequence[np.ndarray] = ()) -> list[list[str]]:
    """Commands that look like actuators acting alike: all one-way or all two-way, with
    typical levels within ALIKE_LEVELS of each other (rotors; a ROV's thrusters), moving
    with one of the group where ``values`` (each command's, as logged) say how (`_comoving`),
    and not one command logged several times (``identical``: sets of names with equal
    values)."""
    logged = dict(zip((p.name for p in commands), values, strict=False))
    ordered = sorted((p for p in commands if p.level > NEUTRAL and not is_set_point(p)),
                     key=lambda p: (p.two_way, p.level))
    groups: list[list[Proposal]] = []
    for proposal in ordered:
        group = groups[-1] if groups else None
        if group and group[0].two_way == proposal.two_way and \
                proposal.level <= ALIKE_LEVELS * group[0].level and any(
                    _comoving(logged.get(p.name), logged.get(proposal.name)) for p in group):
            group.append(proposal)
        else:
            groups.append([proposal])
    names = [[p.name for p in group] for group in groups if len(group) > 1]
    return [group for group in names if frozenset(group) not in identical]


def _comoving(one: np.ndarray | None, other: np.ndarray | None) -> bool:
    """Whether two commands logged side by side move together (or against each other) at
    least ALIKE_CORRELATION of the time: rotors with the collective, a ROV's horizontal
    thrusters with its surge and turns; not a rudder with the ailerons, nor a vertical
    thruster with the horizontal ones. Unknown (not logged side by side): assumed."""
    if one is None or other is None or one.shape != other.shape:
        return True
    both = np.isfinite(one) & np.isfinite(other)
    with np.errstate(all="ignore"):        # a damaged log's huge values overflow: unknown
        if both.sum() < 3 or not np.std(one[both]) > 0 or not np.std(other[both]) > 0:
            return True
        correlation = float(np.corrcoef(one[both], other[both])[0, 1])
    return not np.isfinite(correlation) or abs(correlation) >= ALIKE_CORRELATION


def repeated(commands: list[Proposal], values: list[np.ndarray]) -> set[frozenset[str]]:
    """Sets of commands whose logged values are all equal: one command logged several times
    (the Haizhe AUV's pwm1 … pwm4), never a group whose shares could differ."""
    groups: dict[bytes, list[str]] = {}
    for proposal, value in zip(commands, values, strict=True):
        groups.setdefault(np.nan_to_num(value).tobytes(), []).append(proposal.name)
    return {frozenset(names) for names in groups.values() if len(names) > 1}
