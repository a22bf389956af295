"""What a failure did: the vehicle against the model of the healthy vehicle started from
the measured state at the change test's onset."""

from collections.abc import Mapping

import numpy as np

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.results import Observations
from auvdiag_cli.engine.substitution import rms


def failure_effect(seen: Observations, change: ChangeCheck, healthy: np.ndarray,
                   horizon_steps: int | None, unpredicted: Mapping[str, str] = {}) -> str:
    """What the vehicle did against what the model of the healthy vehicle, started from
    the measured state at the onset, says it would have done, in each signal that changed:
    the failure's effect. The gap is the rms from the onset on (against the model's own
    error before it), and the two values where the first replay from the onset ends (its
    horizon, or the log's end; the last step there where every changed signal has a
    reading): the furthest the model predicts with the skill it has. A signal in
    ``unpredicted`` (name -> its skill, too low to judge it) gets neither: its gap would be
    the model's own error, not the failure's effect."""
    span = _first_replay(seen, change, horizon_steps)
    if span is None:
        return ""
    changed = [n for n in change.changed if n in seen.histories.sensor_names]
    cannot = [name for name in changed if name in unpredicted]
    said = _effect(seen, healthy, [n for n in changed if n not in unpredicted], *span)
    unsaid = "" if not cannot else (
        f"the model of the healthy vehicle cannot say what {', '.join(cannot)} would have "
        "done (its skill on normal logs left out of its training: " + ", ".join(
            f"{name} {unpredicted[name]}" for name in cannot) + ")")
    return "; ".join(part for part in (said, unsaid) if part)


def healthy_from_onset(seen: Observations, change: ChangeCheck, healthy: np.ndarray,
                       horizon_steps: int | None, unpredicted: Mapping[str, str] = {}
                       ) -> np.ndarray | None:
    """The first replay of the healthy vehicle from the onset, per step and sensor, for the
    report to draw beside what the vehicle did: NaN before the onset, after that replay's
    horizon and in the signals of ``unpredicted`` (None: no replay from the onset)."""
    span = _first_replay(seen, change, horizon_steps)
    if span is None:
        return None
    drawn = np.full(healthy.shape, np.nan)
    drawn[span[0]:span[1]] = healthy[span[0]:span[1]]
    names = seen.histories.sensor_names
    drawn[:, [names.index(n) for n in unpredicted if n in names]] = np.nan
    return drawn


def _first_replay(seen: Observations, change: ChangeCheck, horizon_steps: int | None
                  ) -> tuple[int, int] | None:
    """The steps of the first replay from the change test's onset: to its horizon, or the
    log's end (None: no onset, no replay, or under two steps of it)."""
    histories, onset = seen.histories, change.onset_s
    if histories.matching is None or onset is None:
        return None
    start = int(np.searchsorted(histories.time_s, onset))
    stop = len(histories.time_s) if horizon_steps is None else min(
        start + horizon_steps, len(histories.time_s))
    return None if stop - start < 2 else (start, stop)


def _effect(seen: Observations, healthy: np.ndarray, changed: list[str], start: int,
            stop: int) -> str:
    """`failure_effect` in the signals of ``changed`` the model predicts."""
    histories = seen.histories
    matching = histories.matching
    if matching is None or not changed:     # a loop's gain alone: no sensor to compare
        return ""
    columns = [histories.sensor_names.index(name) for name in changed]
    read = np.flatnonzero(np.isfinite(matching.measured[start:stop, columns]).all(axis=1)
                          & np.isfinite(healthy[start:stop, columns]).all(axis=1))
    last = start + int(read[-1]) if read.size and read[-1] > 0 else None
    gaps, ends = [], []
    for name, column in zip(changed, columns, strict=True):
        unit = seen.sensor_units.get(name, "")
        before = matching.measured[:start, column] - matching.modelled[:start, column]
        gap = matching.measured[start:, column] - healthy[start:, column]
        gaps.append(f"{name} {_number(rms(gap))} {unit} rms (before: {_number(rms(before))})")
        if last is not None:
            ends.append(f"{name} {_number(healthy[last, column])} where it read "
                        f"{_number(matching.measured[last, column])} {unit}")
    effect = ("from the onset, the vehicle departs from what the model of the healthy vehicle "
              "says it would have done by " + ", ".join(gaps))
    if last is None:
        return effect
    return (effect + f"; {histories.time_s[last] - histories.time_s[start]:.1f} s after the "
            "onset the healthy vehicle would have read " + ", ".join(ends))


def _number(value: float | None) -> str:
    return "?" if value is None else f"{value:.3g}"
