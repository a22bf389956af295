"""Naming an actuator whose weakness explains the log better than the sensor the pattern
table reads: the one the hypotheses favour, unless another part's hypothesis explains it
about as well and no other judge tells them apart; then both are candidates, not a guess."""

from dataclasses import replace

from auvdiag_cli.engine.hypotheses import Hypothesis, HypothesisTest
from auvdiag_cli.engine.narrowing import tied_with, weak_alone
from auvdiag_cli.engine.results import Finding, Observations
from auvdiag_cli.vehicle.profile import Profile


def name_weakened(seen: Observations, finding: Finding, weak: Hypothesis,
                  test: HypothesisTest, profile: Profile) -> Finding:
    """``weak`` named over the table's sensor, or it and its rival left as the candidates
    where they tie (`narrowing.tied_with`) and the effort their group carries names neither
    alone."""
    rival = tied_with(test, weak)
    if rival is None:
        return apply_weakened_thruster(finding, weak, profile)
    alone = weak_alone(seen, finding.onset_s, finding.detected_at_s)
    if alone in (weak.component, rival.component):
        return apply_weakened_thruster(finding, rival if alone == rival.component else weak,
                                       profile)
    return left_undecided(finding, weak, rival,
                          f"the pattern table reads b as {finding.component}, but ")


def left_undecided(finding: Finding, chosen: Hypothesis, rival: Hypothesis,
                   lead: str = "") -> Finding:
    """Both parts the candidates, neither named: their hypotheses tie."""
    return replace(finding, component=None, candidates=(chosen.component, rival.component),
                   substitution=None, degradation=None).noted(
        f"{lead}{chosen.describe()} and {rival.describe()} explain the log about as well (g "
        f"then stays at {chosen.peak_g_ratio:.0%} and {rival.peak_g_ratio:.0%} of its "
        "threshold at most): the replay cannot tell them apart, and no other judge names "
        "either alone")


def apply_weakened_thruster(finding: Finding, weak: Hypothesis, profile: Profile) -> Finding:
    table_says = finding.component
    finding = replace(finding, component=weak.component, candidates=(weak.component,),
                      substitution=None)
    explained = (f"the pattern table reads b as {table_says}, but the log is explained by "
                 f"{weak.component} ")
    if weak.stuck_at is not None:
        return finding.noted(explained + f"stuck {weak.stuck_at} from the onset (g then stays "
                             f"at {weak.peak_g_ratio:.0%} of its threshold at most)")
    if weak.thrust_fraction == 0.0:
        # A thruster dying in a turn or at low speed raises one bit before the other: the
        # decision window saw only that one, and it is a sensor's row.
        row = next((r for r in profile.pattern if weak.component in r.components), None)
        return replace(finding, case=None if row is None else row.case).noted(
            explained + f"dead from the onset (g then stays at {weak.peak_g_ratio:.0%} of its "
            "threshold at most): its failure raised the bits of its row one after the other")
    return replace(finding, degradation=weak).noted(
        explained + f"giving {weak.thrust_fraction:.0%} of its thrust from the onset "
        f"(g then stays at {weak.peak_g_ratio:.0%} of its threshold at most): a partial "
        "failure, which the paper's table (assumption 3) does not describe")
