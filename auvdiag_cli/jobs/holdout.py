"""Which normal logs train and which are held out to judge: explicit held-out logs, every
fifth log, or the last part in time of a single log."""

from collections.abc import Sequence
from pathlib import Path

import numpy as np

HELD_OUT_FRACTION = 0.2      # of a single log's usable steps, its last part in time


def split_holdout(logs: Sequence[Path], holdout: Sequence[Path]) -> tuple[list[Path], list[Path]]:
    """Explicit held-out logs, or every fifth log (at least one) when there are several; a
    single log is split in time instead (see `train_from_logs`)."""
    if holdout:
        return [p for p in logs if p not in holdout], list(holdout)
    if len(logs) < 2:
        return list(logs), []
    held = [p for i, p in enumerate(logs) if i % 5 == 4] or [logs[-1]]
    return [p for p in logs if p not in held], held


def split_point(usable: np.ndarray, held_out_fraction: float = HELD_OUT_FRACTION) -> int:
    """The index before which 1 - held_out_fraction of the usable steps lie."""
    count = np.cumsum(usable)
    if not count.size or not count[-1]:
        return len(usable)
    return int(np.searchsorted(count, count[-1] * (1 - held_out_fraction))) + 1
