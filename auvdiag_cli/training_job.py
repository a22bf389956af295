"""`auvdiag train`: fit the dynamics model to normal-condition logs and write a model dir."""

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from auvdiag_cli import __version__
from auvdiag_cli.digest import log_digest
from auvdiag_cli.errors import UsageError
from auvdiag_cli.ingest import ingest
from auvdiag_cli.profile import Profile

# The paper's model errors after training (Takai & Ura 1999), for comparison in reports.
PAPER_MODEL_ERROR = {"flow": 0.0175, "yaw_rate": 0.0168}
PAPER_VEHICLE = "twin-burger"


def paper_model_error(profile: Profile) -> dict[str, float]:
    """The paper's figures, for the paper's vehicle only: no other vehicle is comparable."""
    return dict(PAPER_MODEL_ERROR) if profile.name == PAPER_VEHICLE else {}


@dataclass(frozen=True)
class TrainingResult:
    output: Path
    training_logs: int
    heldout_logs: int
    heldout_rms: dict[str, float]
    heldout_mean_abs: dict[str, float]


def split_holdout(logs: Sequence[Path], holdout: Sequence[Path]) -> tuple[list[Path], list[Path]]:
    """Explicit held-out logs, or every fifth log (at least one) when none are given."""
    if holdout:
        return [p for p in logs if p not in holdout], list(holdout)
    if len(logs) < 2:
        raise UsageError("training needs at least two logs (one is held out to measure error)")
    held = [p for i, p in enumerate(logs) if i % 5 == 4] or [logs[-1]]
    return [p for p in logs if p not in held], held


def train_from_logs(logs: Sequence[Path], output: Path, profile: Profile,
                    holdout: Sequence[Path] = (), hidden: int = 32, seed: int = 0,
                    iterations_scale: float = 1.0,
                    progress: Callable[[str], None] = lambda _: None) -> TrainingResult:
    from models.store import save_model
    from models.training import DEFAULT_STAGES, Stage, TrainingLog, free_run_error, train

    training_paths, heldout_paths = split_holdout(logs, holdout)
    if not training_paths:
        raise UsageError("no training logs left after holding out")

    def load(path: Path) -> TrainingLog:
        frame = ingest(path, profile).frame
        for note in frame.slow_commands:
            progress(f"warning: {path.name}: {note}")
        return TrainingLog(path.name, frame.commands, frame.sensors)

    progress(f"reading {len(training_paths)} training and {len(heldout_paths)} held-out logs")
    training = [load(p) for p in training_paths]
    heldout = [load(p) for p in heldout_paths]
    stages = [Stage(s.horizon_steps, max(1, round(s.iterations * iterations_scale)),
                    s.learning_rate) for s in DEFAULT_STAGES]
    try:
        network, normaliser = train(training, hidden=hidden, stages=stages, seed=seed,
                                    progress=progress)
    except ValueError as problem:   # the logs hold too little complete, operating data
        raise UsageError(f"cannot train on {', '.join(p.name for p in training_paths)}: "
                         f"{problem}") from None
    error = free_run_error(network, normaliser, heldout)
    names = profile.sensor_names
    rms = {n: round(v, 6) for n, v in zip(names, error.rms, strict=True)}
    mean_abs = {n: round(v, 6) for n, v in zip(names, error.mean_abs, strict=True)}
    digests = [{"log": p.name, "sha256": log_digest(p)} for p in training_paths]
    metadata = {
        "name": output.name,
        "vehicle": profile.name,
        "profile": profile.source_path,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "tool_version": __version__,
        "dt_s": profile.dt_s,
        "signals": {
            "commands": list(profile.command_names),
            "sensors": [{"name": s.name, "unit": s.unit} for s in profile.sensors],
        },
        "full_scale": profile.full_scales,
        "window_samples": profile.window_samples,
        "thresholds": profile.thresholds,
        "training": {
            "data_sha256": hashlib.sha256(
                "".join(d["sha256"] for d in digests).encode()).hexdigest(),
            "logs": digests,
            "steps": sum(len(t.commands) for t in training),
            "stages": [s.__dict__ for s in stages],
            "seed": seed,
        },
        "heldout_error": {
            "logs": [p.name for p in heldout_paths],
            "rms": rms,
            "mean_abs": mean_abs,
            "paper_rms": paper_model_error(profile),
        },
    }
    save_model(output, network, normaliser, metadata)
    return TrainingResult(output, len(training), len(heldout), rms, mean_abs)
