"""Faults the simulator can inject, named with the profile's component names."""

from dataclasses import dataclass

FAULT_KINDS = {
    "flow_sensor": ("covered", "bias", "drift"),
    "yaw_rate_sensor": ("dead", "bias", "drift"),
    "thruster_0": ("dead", "weak"),
    "thruster_1": ("dead", "weak"),
}


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

    def __post_init__(self) -> None:
        kinds = FAULT_KINDS.get(self.component)
        if kinds is None or self.kind not in kinds:
            valid = "; ".join(f"{c}: {', '.join(k)}" for c, k in FAULT_KINDS.items())
            raise ValueError(f"unknown fault {self.component}:{self.kind} (valid: {valid})")

    def thruster_gain(self, index: int, time_s: float) -> float:
        if self.component != f"thruster_{index}" or time_s < self.onset_s:
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
