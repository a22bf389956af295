"""Which member of a group a departure of its shares names: the match of the departure
with each member's weakness (its signature), and whether the departure tells the best
match from the others (`engine.effort_check`)."""

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from models.effort_directions import weakness_directions

CLEAR_MATCH = 0.8           # a match below this names no one actuator's weakness
# A departure leaning towards one member's signature rather than another's by this many of
# its noise's standard deviations tells the two apart (one-sided, 2.3 % the other way).
TOLD_APART_Z = 2.0


@dataclass(frozen=True)
class ActuatorEffort:
    name: str
    component: str
    group: str
    share: float | None          # of the group's mean effort, over the log's steady time
    normal_share: float | None   # what normal logs give for the same operating conditions
    spread: float | None         # σ of the share between normal logs of this length
    departure: float | None      # share / normal share − 1 (0.10: carries 10 % more)
    ratio: float | None          # the largest z over its threshold (either test); > 1 alarms
    not_judged: str | None       # why not, or None
    # The smallest rise of its share the whole-log test judges over this log (`smallest_rise`)
    smallest_rise_shown: float | None = None
    # Where its group changed within the log: its share from the onset on over its share
    # before, less one (a rotor lost in a log's last seconds barely moves the whole log's).
    since_onset: float | None = None
    driven_alone: bool = False   # its controller drives it alone (`EffortGroup.driven_alone`)
    # Under its threshold, but past the one a looser budget would set, on few normal logs
    # (`models.effort_thresholds.Thresholds.near`): they cannot rule it out.
    near: bool = False
    # Where it is `near`: how many normal logs like the model's would judge this log
    # (`models.effort_thresholds.logs_to_judge`; None: more than it says).
    judged_with_logs: int | None = None

    @property
    def driven_harder(self) -> bool:
        return self.ratio is not None and self.ratio > 1

    @property
    def said(self) -> str:      # its part, as the verdict names it, and its own name
        return self.name if self.component == self.name else f"{self.component} ({self.name})"


def driven_harder(actuator: ActuatorEffort) -> bool:
    return actuator.driven_harder


def _suspect_group(actuators: Sequence[ActuatorEffort],
                   directions: Mapping[str, np.ndarray] | None,
                   departures: Mapping[str, np.ndarray] | None,
                   suspect: Callable[[ActuatorEffort], bool] = driven_harder
                   ) -> tuple[list[ActuatorEffort], np.ndarray, np.ndarray] | None:
    """(The strongest suspect's group, its departures, its members' signatures (members,
    candidates, members)) as `signature_matches` reads them; None: nothing to match."""
    suspects = sorted(filter(suspect, actuators), key=lambda a: -(a.ratio or 0))
    if not suspects:
        return None
    group = [a for a in actuators if a.group == suspects[0].group and a.spread]
    if len(group) < 2:
        return None
    z = (departures or {}).get(group[0].group)
    if z is None or len(z) != len(group):
        z = np.array([((a.share or 0.0) - (a.normal_share or 0.0)) / (a.spread or 1.0)
                      for a in group])
    toward = (directions or {}).get(group[0].group)
    if toward is None or toward.shape[::2] != (len(group), len(group)):
        toward = weakness_directions(len(group))[:, None, :]
    return group, z, toward


def signature_matches(actuators: Sequence[ActuatorEffort],
                      directions: Mapping[str, np.ndarray] | None = None,
                      departures: Mapping[str, np.ndarray] | None = None,
                      suspect: Callable[[ActuatorEffort], bool] = driven_harder
                      ) -> tuple[tuple[str, float], ...]:
    """How well the departures of the strongest suspect's group (``suspect``: which
    actuators are suspects, by default those driven harder), in units of their spreads,
    match each member's weakness, best first: the cosine between them and the signature
    of member i, the best of its candidates. ``directions``: the group's, (members,
    candidates, members), over the whole log (`models.effort_reach.named_signatures`); by
    default its own share up and the others' down alike, the shares averaging to one:
    e_i - 1/m. ``departures``: a group's to match instead of the whole log's (those of a
    change within the log that alarmed, from its start to the end). One weak actuator
    matches its own near 1; a load shared between two, or two weak ones, matches none
    well."""
    found = _suspect_group(actuators, directions, departures, suspect)
    if found is None:
        return ()
    group, z, toward = found
    length = float(np.linalg.norm(z))
    matches = (toward @ z).max(axis=1) / length if length > 0 else np.zeros(len(group))
    return tuple(sorted(((a.name, round(float(m), 2)) for a, m in zip(group, matches,
                                                                     strict=True)),
                        key=lambda item: -item[1]))


def not_told_apart(actuators: Sequence[ActuatorEffort], best: str,
                   directions: Mapping[str, np.ndarray] | None = None,
                   departures: Mapping[str, np.ndarray] | None = None) -> tuple[str, ...]:
    """The members of the best match's group whose weakness the departures do not tell from
    ``best``'s: along the difference of the two signatures, the departure leans towards
    ``best`` by less than TOLD_APART_Z of its noise. Signatures far apart (a group its
    mixer drives member by member) tell any clear match apart; a mixer that moves two
    members' shares nearly alike where the vehicle worked may not."""
    found = _suspect_group(actuators, directions, departures)
    if found is None:
        return ()
    group, z, toward = found
    names = [a.name for a in group]
    if best not in names:
        return ()
    signatures = toward[np.arange(len(group)), np.argmax(toward @ z, axis=1)]
    difference = signatures[names.index(best)] - signatures
    lengths = np.linalg.norm(difference, axis=1)
    lean = np.where(lengths > 0, difference @ z / np.where(lengths > 0, lengths, 1.0), np.inf)
    return tuple(n for n, d in zip(names, lean, strict=True) if d < TOLD_APART_Z)


def clear_suspect(actuators: Sequence[ActuatorEffort],
                   matches: Sequence[tuple[str, float]]) -> bool:
    """Whether the best match is clear and of an actuator driven harder."""
    return bool(matches) and matches[0][1] >= CLEAR_MATCH and any(
        a.name == matches[0][0] and a.driven_harder for a in actuators)


def named_components(actuators: Sequence[ActuatorEffort], matches: Sequence[tuple[str, float]],
                     untold: Sequence[str] = ()) -> tuple[tuple[str, ...], bool]:
    """(The components of the actuators driven harder; in the strongest suspect's group,
    where its departure matches the weakness of one member driven harder clearly
    (CLEAR_MATCH), that member with those it does not tell it from (``untold``,
    `not_told_apart`); and whether there are such.) Another member crossing beside it (a
    slow drift of its share within the log, seen by the test against the log's own
    beginning) is not a second weakness the shares show: two weak members, or a load
    between them, match no one signature."""
    clear = matches[0][0] if matches and matches[0][1] >= CLEAR_MATCH else None
    group = next((a.group for a in actuators if a.name == clear and a.driven_harder), None)
    if group is None:
        return tuple(dict.fromkeys(a.component for a in actuators if a.driven_harder)), False
    component = {a.name: a.component for a in actuators}
    alike = list(dict.fromkeys([component[str(clear)], *(component[n] for n in untold)]))
    return tuple(dict.fromkeys([*alike, *(a.component for a in actuators
                                          if a.driven_harder and a.group != group)])), \
        len(alike) > 1


def named_by_shares(actuators: Sequence[ActuatorEffort], directions: Mapping[str, np.ndarray],
                    changed: Mapping[str, np.ndarray], changed_toward: Mapping[str, np.ndarray]
                    ) -> tuple[tuple[tuple[str, float], ...], tuple[str, ...], bool]:
    """(`signature_matches`, then `named_components`) of the whole log's departures, or of
    the change within the log (``changed``, matched with ``changed_toward``) where the whole
    log names no one clearly: a rotor lost at the log's end barely moves the whole log. The
    best match is told from the others by the departure that alarmed: the change where one
    did."""
    matches = signature_matches(actuators, directions)
    if changed and not clear_suspect(actuators, matches):
        matches = signature_matches(actuators, changed_toward, changed)
    untold = (not_told_apart(actuators, matches[0][0], *((changed_toward, changed) if changed
                                                         else (directions, None)))
              if matches else ())
    return (matches, *named_components(actuators, matches, untold))


def not_ruled_out(actuators: Sequence[ActuatorEffort], directions: Mapping[str, np.ndarray]
                  ) -> tuple[str | None, tuple[tuple[str, float], ...]]:
    """(The component of the actuator few normal logs cannot rule out weak: the strongest
    one past the looser threshold (`ActuatorEffort.near`) where none is driven harder, its
    group's departure matching its weakness clearly and best; None where there is none;
    the matches). A departure matching no one member's weakness is not one weak member."""
    if any(a.driven_harder for a in actuators) or not any(a.near for a in actuators):
        return None, ()
    matches = signature_matches(actuators, directions, suspect=lambda a: a.near)
    best = next((a for a in actuators if matches and a.name == matches[0][0] and a.near), None)
    if best is None or matches[0][1] < CLEAR_MATCH:
        return None, matches
    return best.component, matches
