"""A log judged against its own healthy beginning: a change test on the model's residuals.

The thresholds learnt across logs must allow for the scatter between logs (wind, payload,
trim, a model better on some logs than others). A failure that starts mid-log is seen
sooner against the same log's earlier residuals. The residual judged is the error of the
model's predictor a moment ahead (`models.ahead`: small and steady on a healthy log, where
the replay's error swings with every manoeuvre), or the replay's for a model without one.
For each judged signal, over a window of the profile's `window_samples` ending at every step
(`STRIDE_STEPS`), the residual averaged over the window is compared with the same averages
over all the windows before it that do not overlap it, in units of their spread there:

    z = (mean of this window - mean of the earlier windows) / spread of the earlier windows

Two statistics judge it, each with its own threshold per signal: the window's |z| itself
("window": an abrupt change, seen in the window it happens), and a two-sided CUSUM that adds
up what goes beyond the allowance `DRIFT_ALLOWANCE` window after window, each window's sum
carried on from the window a whole window before it ("sum"):

    S+ = max(0, S+ + z - k),  S- = max(0, S- - z - k),  S = max(S+, S-)

so that a shift that lasts (an engine that stopped pushing, a surface that stuck) builds
up even when no single window stands out, while noise within the allowance does not. Each
way (z and S+ above the prediction, −z and S− below it) is first divided by how far normal
logs typically go that way (`WayScales`, set by calibrate): a failure pushes a signal one
way, and where normal operation goes further the other way, that way no longer sets the
threshold of both. Where the profile says which way a part's weakening moves several
signals, their signed sum is judged as one more signal, one-sided (`change_signatures`).
A signal is judged once the reference holds `REFERENCE_MIN_S` of residuals. The thresholds
are set by `auvdiag calibrate` from the largest of each statistic on normal logs; a model
without them does not run the test. The onset: the run of windows whose sum went beyond
the allowance up to the alarm (back to where the strongest signal's sum last left zero),
then within it the step where that signal's residual most likely shifted (`_dated`). The
signals that crossed within a window of the alarm name the part.
"""

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from auvdiag_cli.engine.change_point import shift_start, shift_ways
from auvdiag_cli.engine.change_signatures import signatures
from auvdiag_cli.engine.change_statistics import (
    STATISTICS,
    STRIDE_STEPS,
    SUM,
    WINDOW,
    WayScales,
    change_statistics,
    stride_of,
)
from auvdiag_cli.vehicle.actuators import Actuator

REFERENCE_MIN_S = 30.0        # the log's own residuals needed before it is judged
# A signal the normal logs let the test judge for less than this, all together, gets no
# threshold from calibrate (`jobs.change_calibration.enough_judged`).
MIN_JUDGED_S = REFERENCE_MIN_S


@dataclass(frozen=True)
class ChangeCheck:
    """The change test on one log."""

    thresholds: Mapping[str, Mapping[str, float]]   # statistic -> judged signal -> threshold
    peaks: Mapping[str, Mapping[str, float]]        # statistic -> judged signal -> largest
    judged_from_s: float | None        # when the reference was long enough; None: never
    alarm_s: float | None = None       # the first step over a threshold
    onset_s: float | None = None       # where, in the run that crossed, it most likely began
    onset_error_s: float = 0.0         # give or take
    since_judged: bool = False         # its sum ran from the first step judged (`check_change`)
    # Signal -> its statistic over its threshold within a window from the alarm (the larger
    # of the two, at its highest there).
    flagged: Mapping[str, float] = field(default_factory=dict)
    # Judged signal -> how much more of the change it carried over the run of windows up to
    # the alarm than before it (`_carried`), where ``flagged`` says only where it ended.
    evidence: Mapping[str, float] = field(default_factory=dict)
    # Each signature judged (`change_signatures`) -> the signals it sums.
    members: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    # Each signal that crossed or carried some of the change -> the way its residual moved
    # from the onset ("above" or "below" the prediction).
    ways: Mapping[str, str] = field(default_factory=dict)
    # The loops judged (`models.tracking`): their gain, judged below its usual value only.
    loops: tuple[str, ...] = ()
    # Per step, each of ``ratio_names`` (signals and signatures with a threshold) over its
    # threshold, the larger of the two statistics (NaN before judged): what the report draws.
    ratio_names: tuple[str, ...] = ()
    ratios: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def changed(self) -> tuple[str, ...]:
        """The signals that changed: each flagged, and the members of a flagged signature."""
        return tuple(dict.fromkeys(
            n for name in self.flagged for n in self.members.get(name, (name,))))

    @property
    def judged(self) -> bool:
        return self.judged_from_s is not None and any(self.thresholds.values())

    def describe(self) -> str:
        if not self.judged:
            return (f"not judged (the log is too short: needs {REFERENCE_MIN_S:.0f} s of its "
                    "own residuals as its reference)")
        ratios: dict[str, float] = {}
        for statistic, limits in self.thresholds.items():
            for name, limit in limits.items():
                value = self.peaks.get(statistic, {}).get(name)
                if value is not None and limit > 0:
                    ratios[name] = max(ratios.get(name, 0.0), value / limit)
        if self.alarm_s is None:
            worst = max(ratios, key=lambda n: ratios[n], default=None)
            # What came before is its reference: a change there is not seen (a log that
            # fails within its first seconds), and a short log is judged only briefly.
            return (f"no change after {self.judged_from_s:.1f} s against the log's own "
                    "beginning before it" + (
                        "" if worst is None else f" (largest: {worst} at "
                                                 f"{ratios[worst]:.0%} of its threshold)"))
        which = ", ".join(f"{n} {r:.1f}x its threshold" + (
            f" ({self.ways[n]} the prediction)" if n in self.ways else
            " (the loop gives less rate than usual for what it answers)" if n in self.loops
            else "")
            for n, r in self.flagged.items())
        since = (f"or earlier (its sum ran from the first step judged, {self.judged_from_s:.1f}"
                 " s: it may lie in the reference)" if self.since_judged else
                 f"(up to {self.onset_error_s:.1f} s either way)")
        return (f"changed against the log's own beginning from ~{self.onset_s:.1f} s {since}, "
                f"detected at {self.alarm_s:.1f} s: {which}")


def _carried(ratios: np.ndarray, first: int, at: int) -> np.ndarray:
    """Per signal, its ratio to its threshold averaged from step ``first`` (the start of the
    run of windows that crossed) to ``at`` (the alarm), less its average before the run,
    never below 0. The part that failed moves what it moves from the onset on, though some
    of it stays under its threshold; what else crosses near the alarm is often the
    vehicle's answer to the failure. Before the run is each signal's own usual level (a
    noisy signal sits nearer its threshold), which carries nothing."""
    run = np.nan_to_num(ratios[first:at + 1], nan=0.0).mean(axis=0)
    before = ratios[:first]
    known = np.isfinite(before)
    usual = np.where(known, before, 0.0).sum(axis=0) / np.maximum(known.sum(axis=0), 1)
    return np.asarray(np.maximum(run - usual, 0.0))


def _run_start(sums: np.ndarray, at: int, window: int, stride: int) -> int:
    """The first step of the first window of the run of windows whose sum went beyond the
    allowance up to the alarm at step ``at``: the windows of the alarm's phase, a whole
    window apart, back to the last whose sum was 0 (or the first there is)."""
    end = at - (at - (window - 1)) % stride        # the end of the window judged at ``at``
    while end - window >= window - 1 and sums[end - window] > 0:
        end -= window
    return max(end - window + 1, 0)


def _dated(time_s: np.ndarray, first: int, run: int, at: int, judged_from: int,
           window_s: float) -> tuple[float, float, bool]:
    """(onset_s, its error, whether it may lie in the reference). The run's start alone
    would date the change to noise that lingered in the sum (with a window judged every
    step, some phase's sum nearly always holds some): the error spans the onset up to the
    alarm, a window at least, and back to the log's start where the sum ran from the first
    step judged (the change may lie in the reference, where nothing could show it)."""
    onset, since_judged = float(time_s[first]), run <= judged_from
    return onset, max(window_s, float(time_s[at]) - onset,
                      onset - float(time_s[0]) if since_judged else 0.0), since_judged


def _flagged(ratios: np.ndarray, names: Sequence[str], at: int, window: int
             ) -> dict[str, float]:
    """Each signal over its threshold within a window from the alarm at step ``at``, at
    its highest there, the furthest over first. The first step over a threshold dates the
    detection, but one signal often crosses a few steps before the rest of the change: a
    window holds what windows side by side would have seen at their next end."""
    following = ratios[at:min(at + window, len(ratios))]
    reached = np.where(np.isfinite(following), following, -np.inf).max(axis=0)
    over = {n: round(float(reached[k]), 2) for k, n in enumerate(names) if reached[k] > 1}
    return dict(sorted(over.items(), key=lambda item: -item[1]))


def _ratios(statistics: Mapping[str, np.ndarray], kept: Mapping[str, Mapping[str, float]],
            names: Sequence[str]) -> np.ndarray:
    """Each step's statistics over their thresholds, the larger of the two statistics."""
    ratios = []
    for statistic in (WINDOW, SUM):
        limits = np.array([kept[statistic].get(n, np.inf) for n in names])
        with np.errstate(invalid="ignore"):
            ratios.append(statistics[statistic] / limits)
    return np.asarray(np.fmax(*ratios))


def check_change(residual: np.ndarray, names: Sequence[str],
                 thresholds: Mapping[str, Mapping[str, float]], time_s: np.ndarray,
                 window: int, dt_s: float, actuators: Sequence[Actuator] = (),
                 stride: int | None = STRIDE_STEPS, scales: WayScales | None = None,
                 loops: Collection[str] = (), within_signatures: Collection[str] = (),
                 below_only: Collection[str] = ()) -> ChangeCheck:
    """The test on one log's residuals (columns ``names``), for the signals with a
    threshold (``thresholds``: statistic -> signal -> threshold), each way divided by its
    scale (``scales``, `change_statistics`), and the signatures of the ``actuators`` over
    them and ``within_signatures`` (judged only there) that have one; the ``loops`` and the
    signals ``below_only`` judged below their prediction (or usual gain) only; a window
    judged every ``stride`` steps (None: side by side, as older models were calibrated)."""
    limited = {name for limits in thresholds.values() for name in limits}   # with a threshold
    judged = [i for i, name in enumerate(names) if name in limited or name in within_signatures]
    found = [s for s in signatures(actuators, [names[i] for i in judged]) if s.name in limited]
    names_judged = [*(names[i] for i in judged), *(s.name for s in found)]
    statistics = change_statistics(residual[:, judged], window, round(REFERENCE_MIN_S / dt_s),
                                   found, stride, scales, [names[i] for i in judged],
                                   {*loops, *below_only})
    kept = {s: {n: v for n, v in thresholds.get(s, {}).items() if n in names_judged}
            for s in STATISTICS}
    combined = _ratios(statistics, kept, names_judged)
    started = np.flatnonzero(np.isfinite(statistics[WINDOW]).any(axis=1))
    peaks = {s: {n: round(float(np.nanmax(values[:, k])), 3)
                 for k, n in enumerate(names_judged) if np.isfinite(values[:, k]).any()}
             for s, values in statistics.items()}
    members = {s.name: tuple(names_judged[c] for c in s.signs) for s in found}
    check = ChangeCheck(kept, peaks,
                        round(float(time_s[started[0]]), 3) if started.size else None,
                        members=members, loops=tuple(n for n in names_judged if n in loops),
                        ratio_names=tuple(n for n in names_judged if n in limited),
                        ratios=combined[:, [n in limited for n in names_judged]])
    with np.errstate(invalid="ignore"):
        over = np.flatnonzero((combined > 1).any(axis=1))
    if not over.size:
        return check
    at = int(over[0])
    # The signal furthest over its threshold at the alarm dates the change (one that crossed
    # after it may have moved later: the vehicle's answer).
    strongest = int(np.nanargmax(combined[at]))
    # From where the strongest signal's sum last left zero: the first window of the run that
    # went beyond the allowance, even where a later window alone crossed (a failure takes a
    # second or two to stand out of the noise; the windows before carry part of it).
    run = _run_start(statistics[SUM][:, strongest], at, window, stride_of(window, stride))
    # Within that run, where the strongest signal's own residual shifted: the onset.
    first = run if strongest >= len(judged) else \
        shift_start(residual[:, judged[strongest]], run, at)
    onset, error, since_judged = _dated(time_s, first, run, at, int(started[0]), window * dt_s)
    evidence = {n: round(float(v), 3)
                for n, v in zip(names_judged, _carried(combined, run, at), strict=True)}
    flagged = _flagged(combined, names_judged, at, window)
    moved = [n for n in names_judged if n in names and (n in flagged or evidence[n] > 0)]
    ways = shift_ways(residual, names, [n for n in moved if n not in check.loops], first, at)
    return replace(check, alarm_s=round(float(time_s[at]), 3), onset_s=round(onset, 3),
                   onset_error_s=round(error, 3), flagged=flagged, evidence=evidence,
                   ways=ways, since_judged=since_judged)

