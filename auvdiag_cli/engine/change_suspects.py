"""Which parts could explain what the change test saw: each signal it judges counts for
the parts the profile says move it (`moved_by`, a loop's parts, an actuator's signature),
weighted by how much of the change it carried; and whether the change lies beyond what
the replay can weigh, so that the change test's own evidence names the part."""

from collections.abc import Mapping

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.change_signatures import signature_parts
from auvdiag_cli.engine.detection import look_up
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.vehicle.profile import Profile


def names_a_mover(change: ChangeCheck, profile: Profile) -> bool:
    """Whether the profile says which parts move what changed (`moved_by`): those name the
    part; otherwise the replay's isolation does (pattern table, hypotheses)."""
    return bool(set(change.flagged) & set(change.members)) or any(
        moved_by for name, moved_by in _movers(profile).items() if name in change.flagged)


def _movers(profile: Profile, ways: Mapping[str, str] | None = None
            ) -> dict[str, tuple[str, ...]]:
    """Each signal the change test judges -> the parts that move it (`moved_by`): the
    sensors', then the controller's loops' (a loop's gain is made by its parts). With the
    ``ways`` the signals moved (`ChangeCheck.ways`), a signal that moved the way a part's
    declared weakening moves it (`weakened`) is that part's as well: an engine that stops
    pushing leaves the pitch below the prediction as its autopilot lowers the nose, though
    the elevator is what moves the pitch."""
    movers = {**{s.name: s.moved_by for s in profile.sensors},
              **{loop.name: loop.moved_by for loop in profile.tracking}}
    for actuator in profile.actuators:
        for signal, sign in actuator.weakened:
            moved = movers.get(signal, ())
            if (ways or {}).get(signal) == ("above" if sign > 0 else "below") \
                    and actuator.name not in moved:
                movers[signal] = (*moved, actuator.name)
    return movers


def beyond_the_replay(change: ChangeCheck, judging: Judging) -> bool:
    """Whether every signal that changed is one the replay does not judge and the pattern
    table has no row for them: the hypothesis test, scored by the replay's g, cannot weigh
    such a change at all, so the change test's own evidence names the part."""
    changed = set(change.changed)
    b = {name: int(name in changed) for name in judging.sensor_names}
    return bool(changed) and changed <= set(judging.not_judged) and look_up(
        judging.profile.pattern, b) is None


def change_suspects(flagged: Mapping[str, float], profile: Profile,
                    evidence: Mapping[str, float] | None = None,
                    ways: Mapping[str, str] | None = None) -> list[str]:
    """The parts that could explain the signals that changed, likeliest first: each signal
    counts for the parts that move what it measures (and for a part whose declared weakening
    moves it the way it moved, ``ways``), and a part moving several of them gathers their
    weight. A signal counts by how much of the change it carried from the onset to the alarm
    (``evidence``, `ChangeCheck.evidence`: every judged signal, over its threshold at the
    alarm or not), else by how far it went past its threshold at the alarm (``flagged``); a
    signal barely over is weak evidence, so a part that moved one signal far outweighs one
    that nudged several. A sensor is a suspect only where every signal that crossed is its
    own: a sensor's fault shows in its own readings, while a part that moves the vehicle
    changes what other sensors measure too. On a tie the part that moves comes first: a
    vehicle that stops following its set points the same way has first changed in what moves
    it."""
    weights = dict(evidence) if evidence else {n: r - 1.0 for n, r in flagged.items()}
    weight: dict[str, float] = {}
    movers: set[str] = set()
    for name, moved_by in _movers(profile, ways).items():
        for part in moved_by if name in weights else ():
            weight[part] = weight.get(part, 0.0) + weights[name]
            movers.add(part)
    # A part's signature (`change_signatures`) is evidence for that part alone.
    for name, part in signature_parts(list(weights), profile.actuators).items():
        weight[part] = weight.get(part, 0.0) + weights[name]
        movers.add(part)
    # A signature that crossed is several signals moving together: no one sensor's fault.
    own = set() if signature_parts(list(flagged), profile.actuators) else {
        s.component for s in profile.sensors if s.name in flagged}
    if len(own) == 1:
        (component,) = own
        weight[component] = weight.get(component, 0.0) + sum(
            weights.get(name, 0.0) for name in flagged)
    return sorted(weight, key=lambda part: (-round(weight[part], 6), part not in movers))


def carriers(change: ChangeCheck, most: int = 3) -> str:
    """The signals that carried most of the change from the onset to the alarm (their
    ratio to their thresholds above their usual level), as the note gives them."""
    carried = sorted(((v, n) for n, v in change.evidence.items() if v > 0), reverse=True)
    return "" if not carried else (" (carried from the onset, in shares of each threshold "
                                   "above its usual level: ") + ", ".join(
        f"{n} {v:.2f}" for v, n in carried[:most]) + ")"
