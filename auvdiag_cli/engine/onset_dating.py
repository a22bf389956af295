"""The verdict's onset from the sharpest of the judges that dated the same event.

The judge that saw a fault first dates it as well as its own evidence allows: the effort
shares from the span of windows their change departs over (a few seconds either way), the
commands against the motion from the change point of a gain that builds over a window
(tenths of a second where the actuator stopped outright), the change test from its run of
windows. Where another judge names the same part, saw an event begun by the detection, and
dates it within both their stated errors, they dated one event: the verdict takes the
estimate that states the smaller error (a simulated BlueROV2's vertical thruster stopped at
130.5 s: the shares, which saw it first, 128.0 ± 2.6 s; the commands 130.7 ± 0.2 s)."""

from dataclasses import dataclass, replace

from auvdiag_cli.engine.results import Finding, Observations, Verdict


@dataclass(frozen=True)
class Dating:
    judge: str
    onset_s: float
    error_s: float

    def agrees(self, other: "Dating") -> bool:
        """Whether the two intervals overlap: both may date one event."""
        return abs(self.onset_s - other.onset_s) <= self.error_s + other.error_s


def _datings(seen: Observations) -> list[tuple[Dating, tuple[str, ...]]]:
    """Each judge's dating of the event it alarmed on, and the parts it named (the change
    test's: none of its own; the verdict says which)."""
    found: list[tuple[Dating, tuple[str, ...]]] = []
    change, effort, command = seen.change_check, seen.effort_check, seen.command_check
    # A change that may have begun in the reference (`ChangeCheck.since_judged`) is dated
    # "or earlier": no error bounds it.
    if change is not None and change.alarm_s is not None and change.onset_s is not None \
            and not change.since_judged:
        found.append((Dating("the change test", change.onset_s, change.onset_error_s), ()))
    if effort is not None and effort.alarm_s is not None and effort.onset_s is not None \
            and effort.onset_error_s is not None:
        found.append((Dating("the effort shares", effort.onset_s, effort.onset_error_s),
                      effort.named))
    if command is not None and command.alarm_s is not None and command.began_s is not None \
            and command.began_error_s is not None:
        found.append((Dating("the commands against the motion", command.began_s,
                             command.began_error_s), command.named))
    return found


def sharpest_onset(finding: Finding, seen: Observations) -> Finding:
    """``finding`` with the error of its onset as the judge that dated it states it, and
    its onset from the judge that dates its event most sharply, where another that names
    one of the same parts, begun by the detection, agrees with it and states a smaller
    error."""
    if finding.verdict is not Verdict.FAULT or finding.onset_s is None \
            or finding.detected_at_s is None:
        return finding
    datings = _datings(seen)
    current = next((d for d, _ in datings if abs(d.onset_s - finding.onset_s) < 1e-6), None)
    if current is None:
        return finding
    parts = {finding.component, *finding.candidates} - {None}
    sharper = [d for d, named in datings if set(named) & parts and d.agrees(current)
               and d.onset_s - d.error_s <= finding.detected_at_s
               and d.error_s < current.error_s]
    if not sharper:
        return replace(finding, onset_error_s=current.error_s)
    best = min(sharper, key=lambda d: d.error_s)
    return replace(finding, onset_s=best.onset_s, onset_error_s=best.error_s).noted(
        f"dated by {best.judge}, the sharpest of the judges that saw it: it began at "
        f"~{best.onset_s:.1f} s (give or take {best.error_s:.1f} s; {current.judge}: "
        f"~{current.onset_s:.1f} s, give or take {current.error_s:.1f} s)")
