"""A day's logs always hold some in which the vehicle never operated (bench tests, logs
recorded on deck): training and calibration leave those out with a note, and refuse only
when none is left."""

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeVar

from auvdiag_errors import LogNotOperating, UsageError

Read = TypeVar("Read")


def read_operating(paths: Sequence[Path], read: Callable[[Path], Read],
                   progress: Callable[[str], None], purpose: str
                   ) -> dict[Path, Read]:
    """``read`` of each log in which the vehicle operates, by path (in order); the others
    are left out with a note through ``progress``. ``purpose``: what the logs are for, for
    the refusal ("train on", "calibrate with")."""
    kept: dict[Path, Read] = {}
    for path in paths:
        try:
            kept[path] = read(path)
        except LogNotOperating as skipped:
            progress(f"left out {path.name}: {skipped.problem}")
    if paths and not kept:
        raise UsageError(f"nothing to {purpose}: the vehicle never operates in any of the "
                         f"{len(paths)} log(s) given (never armed, or its commands never "
                         "leave neutral)")
    return kept
