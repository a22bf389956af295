"""How the ALFA aircraft's roll followed its set point after an aileron failed: what the
motion gave any judge to see, flight by flight (`benchmarks/alfa.py` prints it beside the
delays). The roll error is the set point less the measured roll (`nav_info/roll`, as the
shipped `arduplane_carbonz` profile reads them)."""

from collections.abc import Sequence
from pathlib import Path

import numpy as np

SOON_S = 4.0            # "just after the onset"
HARD_TURN_RAD = 0.5     # a roll error this large: a turn the aircraft does not follow
USUAL_QUANTILE = 0.9    # the healthy part passes this error one sample in ten


def roll_error(folder: Path) -> tuple[np.ndarray, np.ndarray, int]:
    """(seconds after the log's start, roll error in rad, the log's start in ns)."""
    from auvdiag_cli import api

    signals = api.read_log(folder, api.load_profile("arduplane_carbonz"))
    measured, wanted = signals.series["roll"], signals.series["roll_sp"]
    times = (measured.times_ns - signals.start_ns) / 1e9
    set_point = np.interp(measured.times_ns, wanted.times_ns, wanted.values)
    return times, set_point - measured.values, signals.start_ns


def roll_after_failure(flights: Sequence[tuple[Path, int, float | None]]) -> list[str]:
    """A table: per flight (folder, onset in ns, detection in s after the onset or None),
    the largest roll error within SOON_S of the onset against what its healthy part passes
    one sample in ten, and when the error first reached HARD_TURN_RAD."""
    rows = [f"| flight | roll error within {SOON_S:g} s of the onset, largest (rad) | its "
            "healthy part passes, one sample in ten (rad) | first roll error of "
            f"{HARD_TURN_RAD:g} rad or more (s after the onset) | log left after the onset (s) "
            "| detected (s after the onset) |", "|---|---|---|---|---|---|"]
    for folder, onset_ns, detected_s in flights:
        times, error, start_ns = roll_error(folder)
        onset_s, size = (onset_ns - start_ns) / 1e9, np.abs(error)
        soon = size[(times >= onset_s) & (times < onset_s + SOON_S)]
        hard = np.flatnonzero((times >= onset_s) & (size >= HARD_TURN_RAD))
        rows.append(
            f"| {folder.name} | {np.nanmax(soon):.2f} | "
            f"{np.nanquantile(size[times < onset_s], USUAL_QUANTILE):.2f} | "
            f"{'–' if not hard.size else f'{times[hard[0]] - onset_s:.1f}'} | "
            f"{times[-1] - onset_s:.1f} | "
            f"{'not found' if detected_s is None else f'{detected_s:.1f}'} |")
    return rows
