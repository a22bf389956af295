"""The change test's thresholds (`engine.change_check`), set by `auvdiag calibrate` from
each judged signal's largest S on the normal logs."""

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from auvdiag_cli.engine.change_check import MIN_JUDGED_S, REFERENCE_MIN_S
from auvdiag_cli.engine.change_columns import change_judged, change_names, loop_names
from auvdiag_cli.engine.change_signatures import below_only, signatures, thresholded
from auvdiag_cli.engine.change_statistics import (
    ABOVE,
    BELOW,
    STATISTICS,
    STRIDE_STEPS,
    SUM,
    WINDOW,
    WayScales,
    below_only_columns,
    each_way,
    larger_way,
    signal_of,
    way_statistics,
)
from auvdiag_cli.engine.results import Diagnosis
from auvdiag_cli.jobs.budget import BudgetThresholds
from auvdiag_cli.vehicle.actuators import Actuator
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

if TYPE_CHECKING:
    from models.change_training import TrainedOnPeaks

# The margin rule (too few logs to fit a law of their peaks) never sets a threshold below
# these. Over an hour's windows even Gaussian window means reach |z| of about 4
# (sqrt(2 ln 2N)). Their sum would cross 5 about 14 times in a million windows a side, but
# residual window means are correlated (a turn lasts several windows) and their sums drift
# further: on simulated normal dives of the paper's mission one reached 6.1 where three
# others peaked at 3.3. And the largest of a handful of normal logs' peaks understates the
# next log's. A law fitted to enough logs, its share checked on each log left out, says
# that from the logs themselves: on the ALFA flights (13-24 calibration logs a fold) the
# floor had set 3-4 of each fold's 14-16 thresholds above the fitted ones, hiding two
# engine failures.
MIN_CHANGE_THRESHOLDS = {WINDOW: 6.0, SUM: 8.0}
# And a fitted law never below these: Gaussian window means reach |z| 4 over an hour of
# windows, and a sum of 4 (allowing a spread a window) about once in four hours; a law
# fitted to logs that all stayed quiet (every sum 0) would otherwise set 0.
MIN_FITTED_THRESHOLDS = {WINDOW: 4.0, SUM: 4.0}
# One normal log whose largest value is this many times the next log's is worth a warning;
# with this many logs judged or more, it is left out (`without_outliers`).
DOMINANCE_WARNING = 2.0
MIN_LOGS_FOR_OUTLIERS = 5
# Logs that reach both ways of a signal needed to tell how far normal operation goes each
# way (`way_scales`); with fewer, the two ways are judged alike. The median of fewer logs'
# largest values is too uncertain to tilt a threshold: simulated vehicles calibrated on five
# (two and the three trained on) alarmed on one more normal mission of ten under the margin
# rule with the ways scaled.
MIN_LOGS_FOR_WAYS = 8
# statistic -> signal -> (its largest value on the normal logs, its threshold)
ChangeThresholds = dict[str, dict[str, tuple[float, float]]]


def change_peaks(residual: np.ndarray, names: Sequence[str], window: int, dt_s: float,
                 actuators: Sequence[Actuator] = (), stride: int | None = STRIDE_STEPS,
                 below_only: Collection[str] = ()
                 ) -> tuple[dict[str, dict[str, float]], dict[str, float]]:
    """Each statistic's largest value per signal and way in a log ("roll above", "roll
    below": `each_way`), and per signature of the ``actuators`` over these signals (NaN
    where it is never judged): what calibrate sets the ways' scales and the thresholds
    from; and how long the test judged each signal and signature there (s)."""
    found = signatures(actuators, names)
    statistics = way_statistics(residual, window, round(REFERENCE_MIN_S / dt_s), found,
                                stride, below_only_columns(names, below_only))
    every = [*each_way(names), *(s.name for s in found)]
    peaks = {statistic: {name: float(np.nanmax(values[:, i])) if np.isfinite(values[:, i]).any()
                         else float("nan") for i, name in enumerate(every)}
             for statistic, values in statistics.items()}
    seconds = np.isfinite(statistics[WINDOW]).sum(axis=0) * dt_s
    judged: dict[str, float] = {}
    for i, name in enumerate(every):      # both ways of a signal are judged alike
        judged[signal_of(name)] = max(judged.get(signal_of(name), 0.0), float(seconds[i]))
    return peaks, {name: round(value, 3) for name, value in judged.items()}


def log_change_peaks(residual: np.ndarray, set_aside: Sequence[str], judged: Sequence[str],
                     model: LoadedModel, profile: Profile
                     ) -> tuple[dict[str, dict[str, float]], dict[str, float]]:
    """Each statistic's largest value per judged signal in one normal log's change
    residual (NaN: too short, or ``set_aside`` in that log: a sensor it never fed), and how
    long the test judged each there (`change_peaks`)."""
    names = change_names(model)
    columns = [names.index(name) for name in judged]
    window = model.card.window_samples or profile.window_samples
    peaks, seconds = change_peaks(residual[:, columns], list(judged), window, profile.dt_s,
                                  profile.actuators,
                                  below_only={*loop_names(model), *below_only(profile.sensors)})
    return ({statistic: {name: float("nan") if signal_of(name) in set_aside else value
                         for name, value in values.items()}
             for statistic, values in peaks.items()},
            {name: 0.0 if name in set_aside else value for name, value in seconds.items()})


@dataclass(frozen=True)
class Outlier:
    """One log's largest value of a statistic on a signal, left out of its threshold."""

    log: int
    statistic: str
    name: str
    value: float
    following: float       # the next log's


@dataclass(frozen=True)
class ChangeEvidence:
    """The signals the change test judges, and each normal log's largest statistics (an
    outlier's left out: NaN): the calibration logs', then those the model keeps of the logs
    it was trained on (`training_change`)."""

    judged: list[str]
    peaks: list[dict[str, dict[str, float]]]
    outliers: tuple[Outlier, ...] = ()
    trained_on: tuple[str, ...] = ()     # the logs trained on, last in ``peaks``
    trained_not_counted: int = 0         # logs trained on whose peaks are of another form
    scales: WayScales = field(default_factory=dict)   # each way's (`way_scales`)
    # signal -> how long the normal logs let the test judge it, all together, where that
    # is too little to set its thresholds (`enough_judged`)
    too_little: Mapping[str, float] = field(default_factory=dict)


def change_evidence(diagnoses: Sequence[Diagnosis], replay_judged: Sequence[str],
                    model: LoadedModel, profile: Profile,
                    trained: Sequence["TrainedOnPeaks"] = (), trained_not_counted: int = 0
                    ) -> ChangeEvidence:
    judged = change_judged(model, replay_judged)
    logs = [log_change_peaks(_residual(d), d.set_aside, judged, model, profile)
            for d in diagnoses]
    ways = [*(peaks for peaks, _ in logs),
            *(_below_only(t.peaks, below_only(profile.sensors)) for t in trained)]
    scales = way_scales(ways, judged)
    return without_outliers(enough_judged(ChangeEvidence(
        thresholded(profile.actuators, profile.sensors, judged),
        [either_way(p, judged, scales) for p in ways],
        trained_on=tuple(t.log for t in trained), trained_not_counted=trained_not_counted,
        scales=scales), [*(seconds for _, seconds in logs), *(t.judged_s for t in trained)]))


def _below_only(peaks: Mapping[str, Mapping[str, float]], names: Collection[str]
                ) -> dict[str, dict[str, float]]:
    """One log's largest values per way without the way above of the signals ``names``,
    judged below only: a model trained before they were so keeps both ways' values."""
    return {statistic: {name: float("nan") if name.endswith(ABOVE) and signal_of(name) in names
                        else value for name, value in values.items()}
            for statistic, values in peaks.items()}


def enough_judged(evidence: ChangeEvidence, seconds: Sequence[Mapping[str, float] | None]
                  ) -> ChangeEvidence:
    """The evidence without the signals (and signatures) that the normal logs, all
    together, let the test judge for less than MIN_JUDGED_S (``seconds``: per log, how long
    it judged each; None: a log trained on before the model recorded it, which leaves the
    total unknown and the signal kept): their values NaN, so that they get no threshold
    and take no share of the budget, and each named in ``too_little`` with its total. A
    threshold must rest on how far the statistic goes when nothing fails, and seconds of it
    say nothing of that: on three ALFA flights of one day, the roll loop's gain, judged
    15.6 s in all, had its thresholds at the floors and alarmed in 5 of 14 flights of the
    other days before anything failed."""
    too_little = {}
    for name in evidence.judged:
        if all(s is not None for s in seconds) and (
                total := sum(s.get(name, 0.0) for s in seconds if s is not None)) < MIN_JUDGED_S:
            too_little[name] = round(total, 1)
    peaks = [{statistic: {n: float("nan") if n in too_little else v for n, v in values.items()}
              for statistic, values in p.items()} for p in evidence.peaks]
    return replace(evidence, peaks=peaks, too_little=too_little)


def way_scales(peaks: Sequence[dict[str, dict[str, float]]], signals: Sequence[str]
               ) -> dict[str, dict[str, tuple[float, float]]]:
    """Per statistic and signal, how far normal logs typically go each way: the median of
    the logs' largest values above and below the prediction, as a pair whose geometric mean
    is 1 (the statistic keeps its units). A failure pushes a signal one way, and normal
    operation need not go as far both ways: on the ALFA flights throttle-ups push the
    forward acceleration far above the predictor, while nothing normal drops it as an
    engine cut does; judged by the larger way as it is, its threshold is set by the way
    normal flying goes furthest. With fewer than MIN_LOGS_FOR_WAYS logs reaching both
    ways, none: judged either way alike."""
    scales: dict[str, dict[str, tuple[float, float]]] = {}
    for statistic in STATISTICS:
        for name in signals:
            above, below = ([p.get(statistic, {}).get(name + way, np.nan) for p in peaks]
                            for way in (ABOVE, BELOW))
            pairs = [(a, b) for a, b in zip(above, below, strict=True)
                     if np.isfinite(a) and np.isfinite(b)]
            if len(pairs) < MIN_LOGS_FOR_WAYS:
                continue
            typical = np.median(np.array(pairs), axis=0)
            if not (typical > 0).all():
                continue
            mean = float(np.sqrt(typical.prod()))
            scales.setdefault(statistic, {})[name] = (round(float(typical[0]) / mean, 4),
                                                      round(float(typical[1]) / mean, 4))
    return scales


def either_way(peaks: dict[str, dict[str, float]], signals: Sequence[str],
                scales: WayScales) -> dict[str, dict[str, float]]:
    """One log's largest values per signal, the larger of its ways each divided by its
    scale (a signal's largest over the log is the larger of its ways' largest), and its
    signatures' as they are."""
    out: dict[str, dict[str, float]] = {}
    for statistic, values in peaks.items():
        combined = {name: value for name, value in values.items()
                    if signal_of(name) == name}                       # the signatures
        for name in signals:
            combined[name] = float(larger_way(
                values.get(name + ABOVE, np.nan), values.get(name + BELOW, np.nan),
                scales.get(statistic, {}).get(name, (1.0, 1.0))))
        out[statistic] = combined
    return out


def _residual(diagnosis: Diagnosis) -> np.ndarray:
    residual = diagnosis.histories.change_residual
    assert residual is not None
    return residual


def _ranked(evidence: ChangeEvidence, statistic: str, name: str) -> list[tuple[float, int]]:
    """(value, log) of every log the statistic judged on the signal, largest first."""
    return sorted(((value, i) for i, p in enumerate(evidence.peaks)
                   if np.isfinite(value := p.get(statistic, {}).get(name, np.nan))),
                  reverse=True)


def _dominant(ranked: list[tuple[float, int]], statistic: str) -> tuple[float, int, float] | None:
    """(value, log, the next log's value) where the largest is DOMINANCE_WARNING times the
    next or more and reaches the statistic's floor (`MIN_CHANGE_THRESHOLDS`: below it, a
    value is one that normal flying reaches, and twice a quiet log's is no sign of a
    failure)."""
    if len(ranked) < 2 or ranked[1][0] <= 0:
        return None
    (largest, log), (following, _) = ranked[:2]
    if largest < DOMINANCE_WARNING * following or largest < MIN_CHANGE_THRESHOLDS[statistic]:
        return None
    return largest, log, following


def without_outliers(evidence: ChangeEvidence) -> ChangeEvidence:
    """The evidence with each log's value that is DOMINANCE_WARNING times the next log's or
    more (and past the statistic's floor) left out, where MIN_LOGS_FOR_OUTLIERS logs or more
    were judged. Within a log, the
    test is how far a change stands out against the log's own beginning; one normal log
    whose statistic is twice every other's is far likelier a log that was not normal (a
    failure, a disturbance) than the tail of normal flying, and kept it would set the
    threshold past every failure like it (on ALFA, one flight labelled normal that loses
    height at high throttle set the sums of five signals at 2.5-4.5 times every other
    flight's). Each one left out is named (`dominated_by_one_log`)."""
    outliers = []
    peaks = [{s: dict(v) for s, v in p.items()} for p in evidence.peaks]
    for statistic in STATISTICS:
        for name in evidence.judged:
            ranked = _ranked(evidence, statistic, name)
            found = _dominant(ranked, statistic) if len(ranked) >= MIN_LOGS_FOR_OUTLIERS else None
            if found is not None:
                largest, log, following = found
                outliers.append(Outlier(log, statistic, name, largest, following))
                peaks[log][statistic][name] = float("nan")
    return replace(evidence, peaks=peaks, outliers=tuple(outliers))


def change_thresholds(evidence: ChangeEvidence, margin: float,
                      fitted: BudgetThresholds | None) -> ChangeThresholds:
    """Each statistic's threshold per signal: the budget's where it fitted the judge (never
    below `MIN_FITTED_THRESHOLDS`), else margin x its largest value on the normal logs,
    never below `MIN_CHANGE_THRESHOLDS`. A signal no log is long enough to judge gets none (the test
    leaves it out)."""
    budgeted = {} if fitted is None else fitted.thresholds("change")
    result: ChangeThresholds = {}
    for statistic in STATISTICS:
        for name in evidence.judged:
            values = [p[statistic][name] for p in evidence.peaks
                      if np.isfinite(p.get(statistic, {}).get(name, np.nan))]
            if not values:
                continue
            largest = max(values)
            fitted_value = budgeted.get((statistic, name))
            threshold = (max(fitted_value, MIN_FITTED_THRESHOLDS[statistic])
                         if fitted_value is not None
                         else max(margin * largest, MIN_CHANGE_THRESHOLDS[statistic]))
            result.setdefault(statistic, {})[name] = (round(largest, 3), round(threshold, 3))
    return result


def dominated_by_one_log(evidence: ChangeEvidence, logs: Sequence[str]) -> list[str]:
    """A warning for each normal log whose largest value of a statistic on a signal was left
    out of that threshold (`without_outliers`), and for each that alone sets one, with fewer
    logs than that judges outliers by."""
    logs = [*logs, *(f"{log} (trained on)" for log in evidence.trained_on)]
    left_out: dict[str, list[str]] = {}
    for o in evidence.outliers:
        left_out.setdefault(logs[o.log], []).append(
            f"{o.name} ({o.statistic}: {o.value:.1f}, {o.value / o.following:.1f}x the next "
            "log's)")
    warnings = [f"{log} left out of the change test's thresholds of {', '.join(which)}: a "
                "log that departs from its own beginning so far beyond every other is taken "
                "for one that was not normal; check it for a failure or a disturbance"
                for log, which in left_out.items()]
    dominated: dict[str, list[str]] = {}
    for statistic in STATISTICS:
        for name in evidence.judged:
            found = _dominant(_ranked(evidence, statistic, name), statistic)
            if found is not None:
                largest, log, following = found
                dominated.setdefault(logs[log], []).append(
                    f"{name} ({statistic}: {largest:.1f}, {largest / following:.1f}x the next "
                    "log's)")
    return warnings + [
        f"{log} alone sets the change test's thresholds of {', '.join(which)}: check that log "
        "for a failure or a disturbance; if it was not normal, calibrate without it"
        for log, which in dominated.items()]


def change_entry(thresholds: ChangeThresholds, evidence: ChangeEvidence,
                 unfed: Mapping[str, Mapping[str, Mapping[str, float]]] | None = None
                 ) -> dict[str, object]:
    """model.json's `change_test` entry: the thresholds, the evidence's way scales and the
    signals it judged too briefly to set any (`enough_judged`); ``unfed``:
    `jobs.change_unfed`."""
    scales = evidence.scales
    return {"thresholds": {s: {n: t for n, (_, t) in v.items()} for s, v in thresholds.items()},
            **({"judged_too_briefly_s": dict(evidence.too_little)}
               if evidence.too_little else {}),
            **({"unfed_thresholds": {i: {s: dict(v) for s, v in by.items()}
                                     for i, by in unfed.items()}} if unfed else {}),
            "largest_normal": {s: {n: peak for n, (peak, _) in v.items()}
                               for s, v in thresholds.items()},
            "way_scales": {s: {n: list(pair) for n, pair in v.items()}
                           for s, v in scales.items()},
            "reference_s": REFERENCE_MIN_S, "stride_steps": STRIDE_STEPS,
            "normal_logs": len(evidence.peaks)}
