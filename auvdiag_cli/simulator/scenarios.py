"""Named dive scenarios: a programme of phases (DMS runs, missions) and an optional fault."""

from dataclasses import dataclass, field, replace

from auvdiag_cli.simulator.faults import Fault, fault_kinds
from auvdiag_cli.vehicle.profile import Profile


@dataclass(frozen=True)
class MissionSpec:
    """Closed-loop following of a rectangle, starting at the origin heading north."""

    length_m: float = 4.0
    width_m: float = 2.0
    clockwise: bool = True
    cruise_speed_mps: float = 0.125
    max_duration_s: float = 400.0


@dataclass(frozen=True)
class ExcitationSpec:
    """Open-loop system-identification run: both commands jump to random levels in
    [-1, 1], each held 1-4 s, so training sees the whole command range (full reverse,
    one thruster against the other) that missions and DMSs rarely reach."""

    duration_s: float = 120.0


@dataclass(frozen=True)
class Phase:
    """One segment of a dive: a DMS by name (``ZA``, ``ZB``, ``ZC``), a mission, or an
    excitation run (logged as ``MISSION``: it is no diagnosis sequence)."""

    name: str
    mission: MissionSpec | None = None
    excitation: ExcitationSpec | None = None


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    phases: tuple[Phase, ...]
    fault: Fault | None = None
    # Once a fault is active, stop this long after onset if the mission has not ended.
    run_after_fault_s: float = 60.0
    extra: dict[str, str] = field(default_factory=dict)


def _mission(**spec: float | bool) -> tuple[Phase, ...]:
    return (Phase("MISSION", MissionSpec(**spec)),)  # type: ignore[arg-type]


PAPER_MISSION = _mission()
DMS_ALL = (Phase("ZA"), Phase("ZB"), Phase("ZC"))

_SCENARIOS = [
    Scenario("paper-normal", "4 m x 2 m clockwise rectangle, no fault (the paper's mission)",
             PAPER_MISSION),
    Scenario("paper-flow-sensor-covered",
             "the paper's experiment: 4 m x 2 m clockwise rectangle, flow sensor covered at "
             "115 s just after a right turn", PAPER_MISSION,
             Fault("flow_sensor", "covered", 115.0)),
    Scenario("mission-ccw", "4 m x 2 m counter-clockwise rectangle, no fault",
             _mission(clockwise=False)),
    Scenario("mission-large-cw", "5 m x 2.5 m clockwise rectangle, no fault",
             _mission(length_m=5.0, width_m=2.5)),
    Scenario("mission-large-ccw", "5 m x 2.5 m counter-clockwise rectangle, no fault",
             _mission(length_m=5.0, width_m=2.5, clockwise=False)),
    Scenario("mission-fast-cw", "5 m x 2.5 m clockwise rectangle at 0.25 m/s, no fault",
             _mission(length_m=5.0, width_m=2.5, cruise_speed_mps=0.25)),
    Scenario("mission-fast-ccw", "4 m x 2 m counter-clockwise rectangle at 0.2 m/s, no fault",
             _mission(clockwise=False, cruise_speed_mps=0.2)),
    Scenario("mission-sprint-cw", "5 m x 2.5 m clockwise rectangle at 0.45 m/s, no fault",
             _mission(length_m=5.0, width_m=2.5, cruise_speed_mps=0.45)),
    Scenario("mission-sprint-ccw", "5 m x 2.5 m counter-clockwise rectangle at 0.45 m/s",
             _mission(length_m=5.0, width_m=2.5, clockwise=False, cruise_speed_mps=0.45)),
    Scenario("excitation", "open-loop random command steps over the whole range, no fault",
             (Phase("MISSION", excitation=ExcitationSpec()),)),
    Scenario("dms-za", "Diagnosis Motion Sequence ZA (both thrusters), no fault", (Phase("ZA"),)),
    Scenario("dms-zb", "Diagnosis Motion Sequence ZB (Thruster 0 only), no fault", (Phase("ZB"),)),
    Scenario("dms-zc", "Diagnosis Motion Sequence ZC (Thruster 1 only), no fault", (Phase("ZC"),)),
    Scenario("routine-and-mission", "ZA, ZB, ZC then the paper's mission, no fault",
             DMS_ALL + PAPER_MISSION),
    Scenario("mission-thruster-0-dead", "paper mission, Thruster 0 dead at 60 s",
             PAPER_MISSION, Fault("thruster_0", "dead", 60.0)),
    Scenario("mission-thruster-1-dead", "paper mission, Thruster 1 dead at 60 s",
             PAPER_MISSION, Fault("thruster_1", "dead", 60.0)),
    Scenario("mission-yaw-rate-sensor-dead", "paper mission, yaw-rate sensor dead at 60 s",
             PAPER_MISSION, Fault("yaw_rate_sensor", "dead", 60.0)),
    Scenario("mission-thruster-0-weak", "paper mission, Thruster 0 at 50 % power from 60 s",
             PAPER_MISSION, Fault("thruster_0", "weak", 60.0, 0.5)),
    Scenario("mission-flow-sensor-bias", "paper mission, flow sensor reads 0.1 m/s high from 60 s",
             PAPER_MISSION, Fault("flow_sensor", "bias", 60.0, 0.1)),
    Scenario("mission-yaw-rate-sensor-drift", "paper mission, yaw-rate sensor drifts by "
             "0.005 rad/s per second from 60 s", PAPER_MISSION,
             Fault("yaw_rate_sensor", "drift", 60.0, 0.005)),
    Scenario("routine-thruster-0-dead", "Thruster 0 dead at 10 s, during ZA; then ZB, ZC and "
             "the mission", DMS_ALL + PAPER_MISSION, Fault("thruster_0", "dead", 10.0),
             run_after_fault_s=150.0),
    Scenario("routine-thruster-1-dead", "Thruster 1 dead at 10 s, during ZA; then ZB, ZC and "
             "the mission", DMS_ALL + PAPER_MISSION, Fault("thruster_1", "dead", 10.0),
             run_after_fault_s=150.0),
    Scenario("za-thruster-0-dead", "ZA then the mission; Thruster 0 dead at 10 s (no ZB/ZC)",
             (Phase("ZA"), *PAPER_MISSION), Fault("thruster_0", "dead", 10.0),
             run_after_fault_s=80.0),
    Scenario("za-thruster-1-dead", "ZA then the mission; Thruster 1 dead at 10 s (no ZB/ZC)",
             (Phase("ZA"), *PAPER_MISSION), Fault("thruster_1", "dead", 10.0),
             run_after_fault_s=80.0),
    Scenario("dms-zb-zc", "ZB then ZC, no fault (a routine run on its own)",
             (Phase("ZB"), Phase("ZC"))),
    Scenario("zb-zc-thruster-0-dead", "ZB then ZC with Thruster 0 dead from the start",
             (Phase("ZB"), Phase("ZC")), Fault("thruster_0", "dead", 0.0)),
    Scenario("zb-zc-thruster-1-dead", "ZB then ZC with Thruster 1 dead from the start",
             (Phase("ZB"), Phase("ZC")), Fault("thruster_1", "dead", 0.0)),
    Scenario("mission-thruster-1-weak", "paper mission, Thruster 1 at 50 % power from 60 s",
             PAPER_MISSION, Fault("thruster_1", "weak", 60.0, 0.5)),
]

MISSION_FAULT_AT_S = 60.0
WEAK_THRUST_FRACTION = 0.5


def _fits(scenario: Scenario, profile: Profile) -> bool:
    dms_known = all(p.name in profile.dms for p in scenario.phases
                    if p.mission is None and p.excitation is None)
    if scenario.fault is None:
        return dms_known
    return dms_known and scenario.fault.kind in fault_kinds(profile).get(
        scenario.fault.component, ())


def _generated(profile: Profile) -> list[Scenario]:
    """Scenarios any vehicle has: each DMS alone, all DMSs then the mission, and each
    component failing during the mission in each way it can fail."""
    every_dms = tuple(Phase(name) for name in profile.dms)
    scenarios = [Scenario(f"dms-{name.lower()}", f"Diagnosis Motion Sequence {name}, no fault",
                          (Phase(name),)) for name in profile.dms]
    if every_dms:
        scenarios.append(Scenario("all-dms-and-mission", f"{', '.join(profile.dms)} then the "
                                  "paper's mission, no fault", every_dms + PAPER_MISSION))
    if every_dms:
        scenarios += [Scenario(
            f"routine-{component.replace('_', '-')}-dead",
            f"{component} dead at 10 s, during {every_dms[0].name}; then the other DMSs and "
            "the mission", every_dms + PAPER_MISSION, Fault(component, "dead", 10.0),
            run_after_fault_s=400.0) for component in fault_kinds(profile)]
    for component, kinds in fault_kinds(profile).items():
        for kind in kinds:
            severity = WEAK_THRUST_FRACTION if kind == "weak" else 0.0
            if kind in ("bias", "drift", "covered"):
                continue     # a bias's size depends on the sensor: named scenarios set it
            what = f"at {severity * 100:.0f} % power" if kind == "weak" else kind
            scenarios.append(Scenario(
                f"mission-{component.replace('_', '-')}-{kind}",
                f"paper mission, {component} {what} from {MISSION_FAULT_AT_S:.0f} s",
                PAPER_MISSION, Fault(component, kind, MISSION_FAULT_AT_S, severity)))
    return scenarios


def scenarios_for(profile: Profile) -> dict[str, Scenario]:
    """The named scenarios that fit the profile's vehicle (its DMSs and components)."""
    named = {s.name: s for s in _SCENARIOS if _fits(s, profile)}
    for scenario in _generated(profile):
        named.setdefault(scenario.name, scenario)
    return named


def get_scenario(name: str, profile: Profile, fault_at_s: float | None = None,
                 severity: float | None = None) -> Scenario:
    """Look a scenario up by name; ``fault_at_s`` moves its fault onset, ``severity`` sets
    how much of its thrust a weakened actuator keeps (0.7: 70 %)."""
    known = scenarios_for(profile)
    try:
        scenario = known[name]
    except KeyError:
        raise KeyError(f"unknown scenario {name!r} for {profile.name} (known: "
                       f"{', '.join(known)})") from None
    if fault_at_s is None and severity is None:
        return scenario
    if scenario.fault is None:
        raise ValueError(f"scenario {name!r} has no fault to move or weaken")
    fault = scenario.fault
    return replace(scenario, fault=replace(
        fault, onset_s=fault.onset_s if fault_at_s is None else fault_at_s,
        severity=fault.severity if severity is None else severity))
