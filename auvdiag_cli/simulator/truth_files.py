"""Where a log's ground truth lies beside it (the simulator writes it there, a test rig may
too); a module of its own, so that finding it imports no log writer."""

from pathlib import Path


def truth_paths(log_path: Path) -> tuple[Path, Path]:
    """Where the ground truth of a log lives: ``NAME.truth.json`` and ``NAME.truth.csv``."""
    stem = log_path.name.split(".")[0]
    return (log_path.with_name(stem + ".truth.json"), log_path.with_name(stem + ".truth.csv"))
