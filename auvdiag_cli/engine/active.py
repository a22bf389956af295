"""Active diagnosis: when the pattern table leaves several candidates (Twin-Burger case 1,
"Thruster 0 or Thruster 1"), Diagnosis Motion Sequences run while the fault was present
decide between them. A DMS moves some actuators only: if its b ≠ 0 the fault is among the
components it moved; if b = 0 those components are healthy (the paper: b ≠ (0,0) on ZB, which
moves Thruster 0 only, means Thruster 0; ZC repeats the test for Thruster 1). A sensor
candidate whose own bit is set stays a candidate either way: a DMS cannot clear a sensor that
misreads the very motion it excites."""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from auvdiag_cli.vehicle.profile import DiagnosisSequence, Profile

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class DmsRun:
    """One DMS segment's outcome, located in absolute time so runs from other logs count."""

    log: str
    name: str
    start_ns: int
    end_ns: int
    b: Mapping[str, int]


@dataclass(frozen=True)
class Evidence:
    log: str
    segment: str
    start_s: float            # seconds from the start of *its* log
    b: Mapping[str, int]
    tested: tuple[str, ...]   # candidates it tests: the actuators it moved, the sensors it flags
    faulty: bool              # b ≠ 0: the fault is among ``tested``; else they are cleared


@dataclass(frozen=True)
class ActiveDiagnosis:
    candidates_before: tuple[str, ...]
    candidates: tuple[str, ...]
    evidence: tuple[Evidence, ...] = ()
    recommended_dms: tuple[str, ...] = ()
    conflict: bool = False


def moved_components(dms: DiagnosisSequence, profile: Profile) -> tuple[str, ...]:
    """Components of the actuators a DMS drives (any non-zero command)."""
    return tuple(command.component for i, command in enumerate(profile.commands)
                 if any(abs(levels[i]) > 0 for _, levels in dms.steps))


def shows_fault_period(run: DmsRun, onset_ns: int) -> bool:
    """The run saw the vehicle with its fault: it ended after the onset and, if it began
    before, caught it (b ≠ 0)."""
    return run.end_ns > onset_ns and (run.start_ns >= onset_ns or any(run.b.values()))


def decide(candidates: Sequence[str], onset_ns: int, runs: Sequence[tuple[DmsRun, int]],
           profile: Profile) -> ActiveDiagnosis:
    """Narrow ``candidates`` with the DMS runs (each with its log's start time, ns) that
    happened while the fault was present (assumption 4: once defective, always defective)."""
    evidence: list[Evidence] = []
    remaining = set(candidates)
    for run, log_start_ns in sorted(runs, key=lambda item: item[0].start_ns):
        tested = tuple(c for c in moved_components(profile.dms[run.name], profile)
                       if c in candidates)
        faulty = any(run.b.values())
        flagged_sensors = {s.component for s in profile.sensors
                           if run.b.get(s.name) and s.component in candidates}
        if not (tested or flagged_sensors) or not shows_fault_period(run, onset_ns):
            continue   # it tests no candidate, or does not show the faulty vehicle
        evidence.append(Evidence(run.log, run.name,
                                        round((run.start_ns - log_start_ns) / NS_PER_S, 3),
                                        run.b, tested + tuple(sorted(flagged_sensors)), faulty))
        remaining = (remaining & (set(tested) | flagged_sensors) if faulty
                     else remaining - set(tested))
    conflict = not remaining
    if conflict:
        remaining = set(candidates)
    kept = tuple(c for c in candidates if c in remaining)
    actuators = remaining & {c.component for c in profile.commands}
    # Only a DMS that moves some but not all remaining actuators can split them.
    recommended = () if len(kept) < 2 else tuple(
        name for name, dms in profile.dms.items()
        if 0 < len(set(moved_components(dms, profile)) & actuators) < len(actuators))
    return ActiveDiagnosis(tuple(candidates), kept, tuple(evidence), recommended, conflict)
