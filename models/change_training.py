"""model.json's `change_training`: the change test's largest statistics on each log a model
was trained on (`auvdiag_cli.jobs.training_change` computes them when `train` writes the
model; `calibrate` counts them beside its own logs)."""

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

# statistic -> signal (or signature) -> the log's largest value (NaN: not judged there)
Peaks = Mapping[str, Mapping[str, float]]


@dataclass(frozen=True)
class TrainedOnPeaks:
    """One log trained on (its name and content digest) and its largest statistics."""

    log: str
    sha256: str
    peaks: Peaks
    # signal (or signature) -> how long the test judged it on the log (s); None: kept
    # before the model recorded it.
    judged_s: Mapping[str, float] | None = None


@dataclass(frozen=True)
class ChangeTraining:
    logs: tuple[TrainedOnPeaks, ...] = ()
    # The steps between the windows the peaks were measured on (None: windows side by
    # side, as before the test judged them more often).
    stride_steps: int | None = None
    # The peaks of each way of a signal apart ("roll above", "roll below"; False: of either
    # way, as before the test scaled each way by its own).
    each_way: bool = False

    def to_json(self) -> dict[str, object]:
        return {"stride_steps": self.stride_steps, "each_way": self.each_way, "logs": [{
            "log": t.log, "sha256": t.sha256, "peaks": {
            statistic: {name: value if math.isfinite(value) else None
                        for name, value in values.items()}
            for statistic, values in t.peaks.items()},
            **({} if t.judged_s is None else {"judged_s": dict(t.judged_s)})}
            for t in self.logs]}

    @classmethod
    def from_json(cls, entry: Mapping[str, Any]) -> "ChangeTraining":
        return cls(tuple(TrainedOnPeaks(str(t["log"]), str(t["sha256"]), {
            str(statistic): {str(name): math.nan if value is None else float(value)
                             for name, value in values.items()}
            for statistic, values in (t.get("peaks") or {}).items()},
            None if t.get("judged_s") is None else {
                str(name): float(value) for name, value in t["judged_s"].items()})
            for t in entry.get("logs", [])),
            None if entry.get("stride_steps") is None else int(entry["stride_steps"]),
            bool(entry.get("each_way", False)))

    def without(self, digests: frozenset[str] | set[str], stride_steps: int
                ) -> tuple[TrainedOnPeaks, ...]:
        """The logs but those whose content digest is among ``digests``; none where their
        peaks are of another statistic (`stale`)."""
        if self.stale(stride_steps):
            return ()
        return tuple(t for t in self.logs if t.sha256 not in digests)

    def stale(self, stride_steps: int) -> bool:
        """Whether the peaks were measured on windows other than ``stride_steps`` apart, or
        either way rather than each way apart: another statistic, whose largest values set
        no threshold of this one."""
        return bool(self.logs) and (self.stride_steps != stride_steps or not self.each_way)
