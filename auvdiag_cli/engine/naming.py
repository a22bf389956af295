"""A fault's candidates, and the component named where there is one: a failed sensor gets
Substituting Control (the model stands in for its signal from the onset)."""

from collections.abc import Sequence
from dataclasses import replace

from auvdiag_cli.engine.closed_loop import replay_closed_loop
from auvdiag_cli.engine.judging import Judging
from auvdiag_cli.engine.results import Finding, Observations
from auvdiag_cli.engine.substitution import substitute
from auvdiag_cli.vehicle.profile import Sensor


def found(seen: Observations, finding: Finding, candidates: Sequence[str], note: str,
           judging: Judging) -> Finding:
    """A fault with these candidates: one of them is named."""
    finding = replace(finding.noted(note), candidates=tuple(candidates))
    if len(candidates) == 1:
        return name_component(seen, finding, candidates[0], judging)
    return finding


def stand_in(seen: Observations, finding: Finding, sensors: Sequence[Sensor]
              ) -> Sensor | None:
    """The failed component's signal the model stands in for: one whose bit is raised,
    else the first the replay judges; none where the model predicts none of them (a
    substitute no better than a guess)."""
    judged = [s for s in sensors if s.name not in seen.not_judged]
    return next((s for s in judged if finding.b.get(s.name)), judged[0] if judged else None)


def name_component(seen: Observations, finding: Finding, component: str, judging: Judging
                    ) -> Finding:
    """The verdict names one component; a failed sensor gets Substituting Control."""
    finding = replace(finding, component=component)
    sensors = [s for s in judging.profile.sensors if s.component == component]
    sensor = stand_in(seen, finding, sensors)
    histories = seen.histories
    matching = histories.matching
    if sensors and sensor is None:
        return finding.noted(f"no substitute for {component}: the replay judges none of "
                             f"its signals ({', '.join(s.name for s in sensors)}), and the "
                             "model's reading of them is no better than a guess")
    if sensor is None or finding.onset_s is None or matching is None:
        return finding
    substitution = substitute(
        sensor, histories.sensor_names, histories.time_s, matching.measured, matching.modelled,
        finding.onset_s, judging.profile.navigation,
        judging.model.card.heldout_error_rms.get(sensor.name))
    if judging.profile.controller is not None and seen.mission_legs:
        substitution = replace(substitution, closed_loop=replay_closed_loop(
            judging.model, judging.profile.controller, histories, finding.onset_s,
            seen.mission_legs, judging.profile.dt_s))
    return replace(finding, substitution=substitution)
