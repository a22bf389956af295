"""Faults the simulator can inject, named with the profile's component names."""

from dataclasses import dataclass

from auvdiag_cli.vehicle.profile import Profile

ACTUATOR_FAULTS = ("dead", "weak")
SENSOR_FAULTS = ("dead", "covered", "bias", "drift")


@dataclass(frozen=True)
class Fault:
    """One component going bad at ``onset_s`` (seconds from the first log message).

    ``severity``: for a weak thruster the remaining fraction of thrust, for a bias the offset
    in the sensor's unit, for a drift the offset growth per second; unused otherwise.
    """

    component: str
    kind: str
    onset_s: float
    severity: float = 0.0

    def check(self, profile: Profile) -> None:
        """ValueError unless the profile's vehicle has this component and it can fail so."""
        kinds = fault_kinds(profile)
        if self.kind not in kinds.get(self.component, ()):
            valid = "; ".join(f"{c}: {', '.join(k)}" for c, k in kinds.items())
            raise ValueError(f"unknown fault {self.component}:{self.kind} for "
                             f"{profile.name} (valid: {valid})")

    def thruster_gain(self, component: str, time_s: float) -> float:
        if self.component != component or time_s < self.onset_s:
            return 1.0
        return 0.0 if self.kind == "dead" else self.severity

    def sensor_reading(self, component: str, true_reading: float, time_s: float) -> float:
        if self.component != component or time_s < self.onset_s:
            return true_reading
        if self.kind in ("covered", "dead"):
            return 0.0
        if self.kind == "bias":
            return true_reading + self.severity
        return true_reading + self.severity * (time_s - self.onset_s)


def fault_kinds(profile: Profile) -> dict[str, tuple[str, ...]]:
    """Every component of the profile's vehicle and the ways it can fail."""
    kinds = {c.component: ACTUATOR_FAULTS for c in profile.commands}
    return kinds | {s.component: SENSOR_FAULTS for s in profile.sensors}
