"""The pattern of the shares: one weak actuator matches its own signature (its share up,
the others' down alike); a load shared by two matches none well, and the report says so;
a clear match names the actuator where the replay cannot weigh what changed, and tells
apart candidates that move the vehicle alike."""

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import cast

import numpy as np
from helpers import observed

from auvdiag_cli.engine.active import ActiveDiagnosis
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.effort_naming import (
    CLEAR_MATCH,
    ActuatorEffort,
    named_components,
    not_told_apart,
    signature_matches,
)
from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.isolation import _measured_instead, name_by_hypotheses
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.narrowing import _narrow_by_effort, unsupported_table
from auvdiag_cli.engine.other_alarms import apply_other_evidence
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.reports.report_build import _actuators
from auvdiag_cli.vehicle.profile import load_profile
from models.effort_reach import named_signatures
from models.store import LoadedModel


def _group(departures: list[float], *harder: int) -> tuple[ActuatorEffort, ...]:
    return tuple(ActuatorEffort(f"motor_{i + 1}", f"motor_{i + 1}", "rotors", 1.0 + d, 1.0,
                                0.01, d, 2.0 if i in harder else 0.5, None)
                 for i, d in enumerate(departures))


def _check(actuators: tuple[ActuatorEffort, ...]) -> EffortCheck:
    return EffortCheck(actuators, 0.01, 20.0, 15.0, ("motor_3",), (),
                       "a damaged propeller or a weak motor", signature_matches(actuators))


def test_one_weak_rotor_matches_its_own_signature():
    check = _check(_group([-0.02, -0.01, 0.06, -0.03], 2))
    (best, match), (_, other) = check.matches[:2]
    assert best == "motor_3" and match > 0.95 and other < 0.1
    assert "the shares match motor_3 weak (0.9" in check.describe()


def test_a_load_between_two_rotors_matches_none_well():
    check = _check(_group([-0.04, -0.04, 0.04, 0.04], 2))
    assert check.matches[0][1] < CLEAR_MATCH
    assert "match no one actuator's weakness well" in check.describe()


def test_no_alarm_no_pattern():
    quiet = tuple(ActuatorEffort(a.name, a.component, a.group, a.share, a.normal_share,
                                 a.spread, a.departure, 0.5, None)
                  for a in _group([0.0, 0.0, 0.01, -0.01], 0))
    assert signature_matches(quiet) == ()


def test_one_clear_weakness_is_named_alone_two_are_named_together():
    # Motor 3's weakness, and motor 1 crossing beside it (a drift within the log): one named.
    clear = _group([0.01, -0.03, 0.06, -0.04], 0, 2)
    assert signature_matches(clear)[0][0] == "motor_3"
    assert named_components(clear, signature_matches(clear))[0] == ("motor_3",)
    # A load between motors 3 and 4 matches no one weakness: both named.
    shared = _group([-0.04, -0.04, 0.04, 0.04], 2, 3)
    assert named_components(shared, signature_matches(shared))[0] == ("motor_3", "motor_4")
    # The clearest match is not among those driven harder: every one driven harder named.
    elsewhere = _group([0.01, -0.03, 0.06, -0.04], 0)
    assert named_components(elsewhere, signature_matches(elsewhere))[0] == ("motor_1",)


def test_a_weak_rotor_the_replay_cannot_judge_is_named_by_its_shares():
    """The change showed in body rates the replay does not judge: a gyro bias that the
    hypothesis test finds to explain the judged yaw rate does not outweigh shares that
    match motor 3 weak alone, begun by the detection; where the replay judges the rates that
    changed, a dead gyro explaining them is named as before, a bias fitted to them not."""
    profile = load_profile(Path("arducopter_quad"))
    judging = cast(Judging, SimpleNamespace(profile=profile))
    check = replace(_check(_group([-0.02, -0.01, 0.06, -0.03], 2)), onset_error_s=3.0)
    test = HypothesisTest((Hypothesis("gyro", "biased", 0.68),
                           Hypothesis("motor_3", "weakened", 1.5, 0.75, "rotor")))
    changed = {"roll_rate": 1, "pitch_rate": 1, "yaw_rate": 1, "climb": 0}
    finding = Finding(verdict=Verdict.FAULT, b=changed, onset_s=16.0, detected_at_s=17.0)
    unjudged = {"roll_rate": "no skill", "pitch_rate": "no skill"}
    named = name_by_hypotheses(observed(check, unjudged), finding, test, judging)
    assert named.component == "motor_3"
    assert "cannot weigh roll_rate, pitch_rate" in named.notes[-1]
    # Every rate judged: a sensor's fault not fitted to the log (dead) that explains it is
    # decided by the hypothesis test (by more than its margin) ...
    dead = HypothesisTest((Hypothesis("gyro", "dead", 0.68), *test.ranked[1:]))
    assert name_by_hypotheses(observed(check, {}), finding, dead,
                              judging).component == "gyro"
    # ... a bias fitted to the log after the onset absorbs the weak rotor's effect there,
    # and does not outweigh the shares (a rotor that died seconds before the log ended).
    fitted = name_by_hypotheses(observed(check, {}), finding, test, judging)
    assert fitted.component == "motor_3"
    assert "gyro biased but fits it to the log after the onset" in fitted.notes[-1]
    # A pair's shares move as one member's weakness whatever moved them (a misread rate
    # the controller answers too): there the fitted bias keeps its name.
    pair = tuple(ActuatorEffort(f"motor_{i}", f"motor_{i}", "pair", 1.0 + d, 1.0, 0.01, d,
                                2.0 if d > 0 else 0.5, None)
                 for i, d in ((3, 0.05), (4, -0.05)))
    paired = EffortCheck(pair, 0.01, 17.0, 15.0, ("motor_3",), (),
                         "a damaged propeller or a weak motor", signature_matches(pair),
                         onset_error_s=3.0)
    assert paired.alone_by(16.0) == "motor_3"
    assert name_by_hypotheses(observed(paired, {}), finding, test,
                              judging).component == "gyro"
    # The shares began after this change: another event, not its cause.
    late = replace(check, onset_s=25.0, alarm_s=30.0)
    assert name_by_hypotheses(observed(late, unjudged), finding, test,
                              judging).component == "gyro"


def test_an_anomaly_no_fault_explains_is_named_by_shares_that_changed_by_its_detection():
    """The replay dates its onset from a window's residual, seconds before the change the
    shares date closely: where no single fault explains the anomaly, shares that match
    motor 3 weak alone and began by the replay's detection name it (the same event); shares
    that changed only after the detection name nothing."""
    judging = cast(Judging, SimpleNamespace(profile=load_profile(Path("arducopter_quad"))))
    check = replace(_check(_group([-0.02, -0.01, 0.06, -0.03], 2)), onset_error_s=3.0)
    test = HypothesisTest((Hypothesis("barometer", "dead", 2.9),
                           Hypothesis("motor_3", "weakened", 3.4, 0.5, "rotor")))
    finding = Finding(verdict=Verdict.FAULT, b={"climb": 1, "yaw_rate": 1}, onset_s=10.0,
                      detected_at_s=17.0)
    assert check.alone_by(10.0) is None           # began after the replay's onset ...
    named = name_by_hypotheses(observed(check, {}), finding, test, judging)
    assert named.component == "motor_3"           # ... but by its detection
    assert "named by the effort its group carries" in named.notes[-1]
    late = replace(check, onset_s=25.0, alarm_s=30.0)
    assert name_by_hypotheses(observed(late, {}), finding, test, judging).component is None


def test_two_candidates_that_move_the_vehicle_alike_are_told_apart_by_their_shares():
    """The table reads b as either of two actuators (a vectored ROV's vertical pair) and
    nothing else decides: the one whose shares match its weakness alone, begun by the
    detection, is kept; shares that point elsewhere, or began after, decide nothing."""
    check = replace(_check(_group([-0.02, -0.01, 0.06, -0.03], 2)), onset_error_s=3.0)
    active = ActiveDiagnosis(("motor_3", "motor_4"), ("motor_3", "motor_4"), (),
                             ("M3", "M4"), False)
    finding = Finding(verdict=Verdict.FAULT, b={"climb": 1}, onset_s=16.0)
    kept, noted = _narrow_by_effort(observed(check, {}), finding, active)
    assert kept.candidates == ("motor_3",) and kept.recommended_dms == ()
    assert "its shares match motor_3 weak alone" in noted.notes[-1]
    elsewhere = replace(active, candidates=("motor_1", "motor_2"))
    assert _narrow_by_effort(observed(check, {}), finding, elsewhere)[0] == elsewhere
    late = replace(check, onset_s=25.0, alarm_s=30.0)
    assert _narrow_by_effort(observed(late, {}), finding, active)[0] == active
    # A sensor among the candidates whose own replay explains the log, closer: the controller
    # answering its misreading moved the shares (a dead gyro spins the vehicle); nothing is
    # decided.
    with_gyro = replace(active, candidates=("motor_3", "gyro"))
    closer = replace(finding, hypotheses=HypothesisTest((
        Hypothesis("gyro", "dead", 0.7), Hypothesis("motor_3", "weakened", 2.0, 0.5, "rotor"))))
    assert _narrow_by_effort(observed(check, {}), closer, with_gyro)[0] == with_gyro
    # Closer but explaining nothing either: the shares decide.
    neither = replace(finding, hypotheses=HypothesisTest((
        Hypothesis("gyro", "dead", 1.4), Hypothesis("motor_3", "weakened", 2.0, 0.5, "rotor"))))
    assert _narrow_by_effort(observed(check, {}), neither, with_gyro)[0].candidates == (
        "motor_3",)
    farther = replace(finding, hypotheses=HypothesisTest((
        Hypothesis("motor_3", "weakened", 1.2, 0.5, "rotor"), Hypothesis("gyro", "dead", 1.4))))
    assert _narrow_by_effort(observed(check, {}), farther, with_gyro)[0].candidates == (
        "motor_3",)
    # A bias fitted to the log absorbs a weak rotor's effect on one signal: it does not count.
    fitted = replace(finding, hypotheses=HypothesisTest((
        Hypothesis("gyro", "biased", 0.8), Hypothesis("motor_3", "weakened", 0.9, 0.5, "rotor"),
        Hypothesis("gyro", "dead", 1.4))))
    assert _narrow_by_effort(observed(check, {}), fitted, with_gyro)[0].candidates == (
        "motor_3",)


def test_a_sensor_the_table_reads_but_no_fault_of_its_own_explains_yields_to_the_shares():
    """A thruster dying as the vehicle dives raises the depth-rate sensor's row alone; no
    fault of that sensor explains the log, the thruster's weakness comes closer, and its
    group's shares match it alone from the onset to the detection: it is named. Where a
    fault of the sensor explains the log, or comes closest (a closed loop answering what a
    dead sensor misreads moves the shares too), or the shares were seen at another time,
    the table stands."""
    check = replace(_check(_group([-0.02, -0.01, 0.06, -0.03], 2)), onset_s=18.0,
                    alarm_s=25.0, onset_error_s=1.5)
    finding = Finding(verdict=Verdict.FAULT, b={"heave": 1}, component="depth_rate_sensor",
                      candidates=("depth_rate_sensor",), onset_s=15.0, detected_at_s=20.0)
    closer = HypothesisTest((Hypothesis("motor_3", "weakened", 1.3, 0.75, "rotor"),
                             Hypothesis("depth_rate_sensor", "dead", 1.7)))
    assert unsupported_table(observed(check, {}), finding, closer, ()) == "motor_3"
    explained = HypothesisTest((Hypothesis("depth_rate_sensor", "stuck", 0.8),
                                Hypothesis("motor_3", "weakened", 1.3, 0.75, "rotor")))
    assert unsupported_table(observed(check, {}), finding, explained, ()) is None
    own_closest = HypothesisTest((Hypothesis("depth_rate_sensor", "dead", 1.2),
                                  Hypothesis("motor_3", "weakened", 1.3, 0.75, "rotor")))
    assert unsupported_table(observed(check, {}), finding, own_closest, ()) is None
    # The shares' event (16.5 s to 25 s) overlaps the replay's (15 s to 20 s); one that
    # began after the detection is another event.
    late = replace(check, onset_s=24.0, alarm_s=30.0)
    assert unsupported_table(observed(late, {}), finding, closer, ()) is None


def _thrust_lost(named: tuple[str, ...], crossed_s: float, rests_on: tuple[str, ...] | None
                 ) -> CommandCheck:
    """The commands against the motion: ``named`` short of thrust from a window that
    crossed at ``crossed_s`` (45 s windows), resting on ``rests_on``."""
    return CommandCheck(("thruster_1", "thruster_3"), {"thruster_1": 0.1, "thruster_3": 0.1},
                        {}, np.zeros((1, 2)), (), crossed_s + 40.0, crossed_s, named,
                        {"thruster_1": 0.9}, 0.37, 45.0, "thrust lost", rests_on)


def test_what_the_commands_measured_on_one_thruster_names_it_where_the_replay_cannot():
    """A horizontal thruster weakened mid-mission: the replay's heave g crosses, marginally,
    and the table reads the depth-rate sensor. Where no fault of that sensor explains it and
    the commands against the motion measure one thruster short of thrust, resting on no
    signal of that sensor, it is named; where the check rests on the depth rate (a misread
    depth would look the same), or began after the detection, the table stands. Where the
    hypotheses that explain the log are of several thrusters about as well, the thruster the
    commands measured is named, not the best by a hair."""
    profile = load_profile(Path("bluerov2"))
    depth = next(s for s in profile.sensors if s.component == "depth_rate_sensor")
    finding = Finding(verdict=Verdict.FAULT, b={"heave": 1}, component="depth_rate_sensor",
                      candidates=("depth_rate_sensor",), onset_s=59.0, detected_at_s=66.4)
    closer = HypothesisTest((Hypothesis("thruster_5", "weakened", 1.02, 0.75, "thruster"),
                             Hypothesis("thruster_3", "weakened", 1.14, 0.75, "thruster"),
                             Hypothesis("depth_rate_sensor", "dead", 1.9)))
    short = _thrust_lost(("thruster_3",), 74.5, ("surge", "yaw_rate"))
    seen = replace(observed(None, {}, "bluerov2"), command_check=short)
    assert unsupported_table(seen, finding, closer, profile.sensors) == "thruster_3"
    on_depth = replace(seen, command_check=replace(short, rests_on=(depth.name,)))
    assert unsupported_table(on_depth, finding, closer, profile.sensors) is None
    later = replace(seen, command_check=_thrust_lost(("thruster_3",), 115.0, ("surge",)))
    assert unsupported_table(later, finding, closer, profile.sensors) is None
    pair = replace(seen, command_check=_thrust_lost(("thruster_1", "thruster_3"), 74.5, ()))
    assert unsupported_table(pair, finding, closer, profile.sensors) is None
    # Several thrusters explain the replay's g about as well: the measured one is named.
    undecided = HypothesisTest((Hypothesis("thruster_5", "weakened", 0.80, 0.75, "thruster"),
                                Hypothesis("thruster_6", "weakened", 0.85, 0.75, "thruster"),
                                Hypothesis("thruster_1", "weakened", 1.25, 0.75, "thruster")))
    first = replace(seen, command_check=_thrust_lost(("thruster_1",), 74.5, ("surge",)))
    alarmed = replace(finding, detected_at_s=68.3)
    named = _measured_instead(first, alarmed, undecided)
    assert named is not None and named.component == "thruster_1"
    assert named.substitution is None and named.degradation is None
    assert "the commands against the motion name thruster_1 alone" in named.notes[-1]
    # A decisive hypothesis, none measured, or a sensor's hypothesis best: as before.
    decisive = HypothesisTest((undecided.ranked[0],
                               Hypothesis("thruster_6", "weakened", 1.9, 0.75, "thruster"),
                               undecided.ranked[2]))
    assert _measured_instead(first, alarmed, decisive) is None
    assert _measured_instead(replace(first, command_check=None), alarmed, undecided) is None
    sensed = HypothesisTest((Hypothesis("dvl", "biased", 0.8), *undecided.ranked))
    assert _measured_instead(first, alarmed, sensed) is None


def test_a_member_the_clear_match_leaves_out_is_not_described_as_driven_harder():
    # Motor 4's share fell over the log; it crossed only against the log's own beginning.
    actuators = _group([-0.02, -0.01, 0.06, -0.05], 2, 3)
    check = EffortCheck(actuators, 0.01, 20.0, 15.0, named_components(actuators, signature_matches(
        actuators))[0], (), "a damaged propeller or a weak motor", signature_matches(actuators))
    assert check.named == ("motor_3",)
    assert "motor_3 carries 6% more" in check.describe()
    assert "motor_4" not in check.describe().split(":")[0]


def test_a_change_within_the_log_is_matched_by_the_departure_that_alarmed():
    """A rotor lost in a log's last seconds barely moves the whole log's shares, whose
    pattern is then the log's own offset from the normal logs; the change that alarmed
    (from its start to the end, against the log before it) carries the rotor's: the match
    is made on it, and names motor 1 alone."""
    whole = _group([0.003, 0.006, -0.012, 0.003], 0)
    assert signature_matches(whole)[0][0] != "motor_1"
    changed = {"rotors": np.array([4.0, -1.5, -1.2, -1.3])}
    matches = signature_matches(whole, None, changed)
    assert matches[0][0] == "motor_1" and matches[0][1] > 0.95
    assert named_components(whole, matches)[0] == ("motor_1",)


def test_a_rotor_that_stopped_matches_its_signature_with_the_tilt_balance():
    """A quad X whose rotor stopped: the controller pushes it to its limit and eases its
    diagonal partner to keep the vehicle level, the other two near normal. That pattern is
    0.82 from the plain signature (about the naming threshold); the profile's mix gives
    the tilt balance, whose direction names motor 1 alone, its partner matching least."""
    profile = load_profile(Path("arducopter_quad"))
    (group,) = profile.effort_groups
    assert group.balance is not None and group.reach is None
    stopped = _group([0.04, -0.04, 0.0, 0.0], 0)
    z = np.array([4.0, -4.0, 0.0, 0.0])
    plain = dict(signature_matches(stopped, None, {"rotors": z}))
    assert 0.8 < plain["motor_1"] < 0.83
    toward = named_signatures(group, np.ones((10, 4)), np.ones(4), np.ones(4))
    balanced = signature_matches(stopped, {"rotors": toward}, {"rotors": z})
    assert balanced[0] == ("motor_1", 1.0) and balanced[-1][0] == "motor_2"
    # A rotor that still gives most of what it is asked for keeps its plain match.
    weak = _group([0.06, -0.02, -0.02, -0.02], 0)
    assert signature_matches(weak, {"rotors": toward})[0] == ("motor_1", 1.0)
    # Groups without a mix that reaches every direction keep their own signatures.
    assert load_profile(Path("crazyflie")).effort_groups[0].balance is None
    assert all(g.balance is None for g in load_profile(Path("bluerov2")).effort_groups
               if g.reach is not None)


def test_a_part_whose_output_is_named_otherwise_is_said_as_the_verdict_names_it():
    """A BlueROV2's outputs are motor_1 … motor_6, its parts thruster_1 … thruster_6: the
    effort says both, never the output's name alone beside a verdict naming the part."""
    pair = (ActuatorEffort("motor_5", "thruster_5", "vertical", 1.08, 1.0, 0.01, 0.08, 2.0,
                           None),
            ActuatorEffort("motor_6", "thruster_6", "vertical", 0.92, 1.0, 0.01, -0.08, 0.5,
                           None))
    text = EffortCheck(pair, 0.01, 66.0, 62.0, ("thruster_5",), (), "a weak motor",
                       signature_matches(pair)).describe()
    assert text.startswith("thruster_5 (motor_5) carries 8% more of the effort")
    assert "the shares match thruster_5 (motor_5) weak (1.00; the next, thruster_6 (motor_6)" \
        in text
    assert _check(_group([-0.02, -0.01, 0.06, -0.03], 2)).describe().startswith("motor_3 carr")


def test_members_whose_signatures_lie_close_are_named_together_until_the_change_leans():
    """A vectored ROV's mix under way moves a weak thruster's shares nearly as it moves a
    neighbour's (signatures at cosine 0.9, in the noise's own coordinates): a change along
    one, a few of its noise's σ in size, matches it best but leans towards it by less than
    TOLD_APART_Z along the difference, and both are named; a change far larger, or one
    along signatures far apart (the plain ones), names it alone."""
    close = np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.9, 0.19 ** 0.5, 0.0, 0.0])
    signatures = {"rotors": np.array([close[0], -close[0], close[1], -close[1]])[:, None, :]}
    actuators = _group([0.06, -0.03, 0.0, -0.03], 0)
    for size, alone in ((5.0, False), (25.0, True)):
        change = {"rotors": size * close[0]}
        matches = signature_matches(actuators, signatures, change)
        assert matches[0] == ("motor_1", 1.0) and matches[1][0] == "motor_3"
        untold = not_told_apart(actuators, "motor_1", signatures, change)
        named, together = named_components(actuators, matches, untold)
        assert named == (("motor_1",) if alone else ("motor_1", "motor_3"))
        assert together is not alone
    plain = {"rotors": 5.0 * (np.eye(4)[0] - 0.25) / np.linalg.norm(np.eye(4)[0] - 0.25)}
    assert not_told_apart(actuators, "motor_1", None, plain) == ()
    check = EffortCheck(actuators, 0.01, 20.0, 15.0, ("motor_1", "motor_3"), (), "",
                        (("motor_1", 1.0), ("motor_3", 0.9)), cannot_tell_apart=True)
    assert "leans too little towards one to tell which is weak" in check.describe()


def test_a_pair_the_shares_cannot_tell_apart_is_told_by_the_commands_against_the_motion():
    """Thrusters 1 and 3 under way move the shares nearly alike; the commands against the
    motion, which see each act on the vehicle its own way, name thruster 1 alone: the
    verdict names it, and where they saw it first, it was detected then. Where they name
    neither, or both, the pair stands."""
    profile = load_profile(Path("bluerov2"))
    judging = Judging((), {}, 1, 1, profile, {}, cast(LoadedModel, None))
    pair = EffortCheck(_group([0.06, -0.03, 0.0, -0.03], 0), 0.01, 80.0, 60.0,
                       ("thruster_1", "thruster_3"), (), "", (("motor_1", 0.98),
                                                               ("motor_3", 0.11)),
                       cannot_tell_apart=True)
    seen = replace(observed(None, {}, "bluerov2"), effort_check=pair)
    normal = Finding(verdict=Verdict.NORMAL, b={"surge": 0})
    told = apply_other_evidence(replace(seen, command_check=_thrust_lost(
        ("thruster_1",), 74.5, ())), normal, judging)
    assert told.verdict is Verdict.FAULT and told.component == "thruster_1"
    assert "which tells thruster_1 from the others" in told.notes[-1]
    for motion in (("thruster_2",), ("thruster_1", "thruster_3")):
        untold = apply_other_evidence(replace(seen, command_check=_thrust_lost(
            motion, 74.5, ())), normal, judging)
        assert untold.component is None and untold.candidates == ("thruster_1", "thruster_3")
        assert "one of thruster_1 or thruster_3, which the shares cannot tell apart" \
            in untold.notes[-1]
    # Members the shares told apart are named as they were.
    both = replace(pair, cannot_tell_apart=False)
    assert both.told_by(("thruster_1",)) == ("thruster_1", "thruster_3")
    # Seen first by the commands against the motion (their alarm at 114.5 s, their first
    # window over from 29.5 s): detected then, from the shares' onset where it comes before.
    late = replace(seen, command_check=_thrust_lost(("thruster_1",), 74.5, ()))
    for onset, dated in ((100.0, 100.0), (120.0, 29.5)):
        found = apply_other_evidence(replace(late, effort_check=replace(
            pair, alarm_s=130.0, onset_s=onset)), normal, judging)
        assert (found.detected_at_s, found.onset_s) == (114.5, dated)
    assert told.detected_at_s == 80.0 and told.onset_s == 60.0
    # The report's JSON says the pair is one the shares cannot tell apart.
    part = _actuators(pair)
    assert part is not None and part.cannot_tell_apart
    assert part.named == ("thruster_1", "thruster_3")
    told_apart = _actuators(both)
    assert told_apart is not None and not told_apart.cannot_tell_apart
