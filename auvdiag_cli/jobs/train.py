"""`auvdiag train`: fit the dynamics model to normal-condition logs, measure its skill on
held-out normal data, choose the prediction horizon, and write a model directory."""

import hashlib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from auvdiag_cli import __version__
from auvdiag_cli.digest import log_digest
from auvdiag_cli.engine.envelope import envelope_entry
from auvdiag_cli.engine.start_check import learn_start_state, start_reading
from auvdiag_cli.jobs.candidates import Candidates, NetworkFit, fit_candidates
from auvdiag_cli.jobs.effort import learn_effort_model
from auvdiag_cli.jobs.healthy import NO_HEALTHY_PARTS, HealthyParts
from auvdiag_cli.jobs.heldout_thresholds import heldout_thresholds, raised
from auvdiag_cli.jobs.holdout import HELD_OUT_FRACTION
from auvdiag_cli.jobs.relate import learn_relations
from auvdiag_cli.jobs.skill_record import skill_metadata
from auvdiag_cli.jobs.tracking_fit import tracking_entry
from auvdiag_cli.jobs.training_change import training_change_peaks
from auvdiag_cli.jobs.training_logs import (
    ReadLog,
    median_rates,
    read_and_split,
    scoring_log,
    split_in_time,
    with_inputs_held,
)
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import UsageError
from models.ahead import AheadLog, fit_ahead
from models.card import Refused, StartReference
from models.effort_model import EffortModel
from models.fast import NETWORK, PREDICTOR_KINDS
from models.relation_forms import Relations
from models.skill import (
    HORIZON_CANDIDATES_S,
    HorizonScore,
    ScoringLog,
    assess,
    choose_horizon,
)

if TYPE_CHECKING:
    from models.store import LoadedModel

@dataclass(frozen=True)
class TrainOptions:
    """How `train_from_logs` trains; the defaults are `auvdiag train`'s."""

    holdout: tuple[Path, ...] = ()     # held-out logs (none: the training logs' last part)
    hidden: int = 32                   # size of the recurrent context
    seed: int = 0
    iterations_scale: float = 1.0      # every stage's iterations times this
    horizon_s: float | None = None     # None: chosen by validation; inf: the free run
    keep_unskilled: bool = False       # write the model even when nothing can be judged
    predictors: tuple[str, ...] = PREDICTOR_KINDS   # the kinds a signal may be read from
    healthy: HealthyParts = NO_HEALTHY_PARTS        # only these parts of the logs listed


DEFAULT_TRAINING = TrainOptions()


def network_asked(predictors: Sequence[str]) -> bool:
    """Whether a signal may be read from the network alone: asked for, or the only choice
    left where the least-squares model is not (the refined one alone may not be kept)."""
    return NETWORK in predictors or "linear" not in predictors


@dataclass(frozen=True, kw_only=True)
class TrainingResult:
    output: Path
    written: bool                 # False: no signal has skill and the model was not kept
    training_logs: int
    heldout_logs: int
    heldout_split: str            # how the held-out data were chosen
    scores: list[HorizonScore]    # every horizon tried
    chosen: HorizonScore
    operating_hours: float
    logged_rates_hz: dict[str, float]   # per signal, median over the training logs
    command_relations: Relations | Refused   # how the commands follow the motion
    start_state: StartReference                     # where normal logs start (or why not)
    effort: EffortModel | Refused                   # each actuator's share of the effort
    effort_notes: tuple[str, ...] = ()  # logs the effort model left out, and why
    by_predictor: dict[str, list[HorizonScore]] = field(default_factory=dict)
    predictor_notes: tuple[str, ...] = ()   # predictors left out, and why
    input_names: tuple[str, ...] = ()       # measured inputs driving it beside the commands
    # The profile's g thresholds the held-out logs raised ('mode signal from -> to').
    thresholds_raised: tuple[str, ...] = ()
    # signal -> the largest |value| the logs learnt from reached (`engine.envelope`).
    envelope: Mapping[str, float] = field(default_factory=dict)

    @property
    def judges_anything(self) -> bool:
        """A signal has skill, some actuator's commands can be judged against the motion, or
        some actuator's share of the effort can be judged."""
        relations, effort = self.command_relations, self.effort
        return bool(self.chosen.judged) or (
            not isinstance(relations, Refused) and relations.judges_anything) or (
            isinstance(effort, EffortModel) and effort.judges_anything)


def horizon_candidates(profile: Profile, horizon_s: float | None) -> list[float | None]:
    """Horizons to score: the one asked for (``inf``: free run), or every candidate (None:
    choose) not shorter than g's window."""
    if horizon_s is not None:
        return [None if math.isinf(horizon_s) else horizon_s]
    shortest = profile.window_samples * profile.dt_s
    return [h for h in HORIZON_CANDIDATES_S if h is None or h >= shortest]


def train_from_logs(logs: Sequence[Path], output: Path, profile: Profile,
                    options: TrainOptions = DEFAULT_TRAINING,
                    progress: Callable[[str], None] = lambda _: None,
                    trainer: Callable[..., Any] | None = None) -> TrainingResult:
    """Train on normal ``logs`` and write the model to ``output`` (where it judges
    anything, or ``options.keep_unskilled``). ``trainer``: `models.training.train` unless
    another is given (benchmarks compare)."""
    training_paths, heldout_paths, every = read_and_split(logs, options.holdout, profile,
                                                          progress, options.healthy)
    read = [every[p] for p in training_paths]
    read_heldout = [every[p] for p in heldout_paths]
    training, heldout = with_inputs_held(read, read_heldout, profile, progress)
    rates = median_rates([r.rates_hz for r in read], [*profile.command_names,
                                                      *profile.sensor_names])
    split = f"{len(heldout)} held-out log(s)"
    if not heldout:
        training[0], tail = split_in_time(training[0])
        heldout, split = [tail], f"the last {HELD_OUT_FRACTION:.0%} of {training_paths[0].name}"
    fit_network, stages = _network_fit(training, options, progress, trainer)
    try:
        fitted = fit_candidates(training, heldout, profile.sensor_names, profile.dt_s,
                                horizon_candidates(profile, options.horizon_s),
                                options.predictors,
                                fit_network, progress)
    except ValueError as problem:   # the logs hold too little complete, operating data
        raise UsageError(f"cannot train on {', '.join(p.name for p in training_paths)}: "
                         f"{problem}") from None
    hours = sum(_complete_steps(t) for t in training) * profile.dt_s / 3600
    progress("learning the command relations, the start state and the effort shares")
    relations, start_state = _learn_beside_the_model(read, read_heldout, training, profile)
    effort, effort_notes = learn_effort_model([r.relation for r in [*read, *read_heldout]],
                                              profile)
    envelope = envelope_entry([r.relation.sensors[r.relation.usable]
                               for r in [*read, *read_heldout]], profile.sensor_names)
    result = TrainingResult(
        envelope=envelope["sensors"], output=output, written=False,
        training_logs=len(training), heldout_logs=len(heldout), heldout_split=split,
        scores=fitted.scores, chosen=choose_horizon(fitted.scores), operating_hours=hours,
        logged_rates_hz=rates, command_relations=relations, start_state=start_state,
        effort=effort, effort_notes=tuple(effort_notes), by_predictor=fitted.by_kind,
        predictor_notes=fitted.notes, input_names=profile.input_names)
    result = replace(result, written=result.judges_anything or options.keep_unskilled)
    if result.written:
        metadata = _metadata(output, profile, training_paths, training, heldout, result,
                             stages, options.seed)
        metadata |= {"envelope": envelope,
                     "command_relations": relations.to_json(),
                     "start_state": start_state.to_json(), "effort": effort.to_json(),
                     "ahead_predictor": _fit_ahead(training, heldout, bool(read_heldout),
                                                     profile, progress),
                     "tracking": tracking_entry(profile, [*training, *heldout], progress)}
        raised_by_heldout = _save(output, fitted, metadata, profile,
                                  (training_paths, heldout_paths), options, progress)
        result = replace(result, thresholds_raised=tuple(raised_by_heldout))
    return result


def _network_fit(training: Sequence[ScoringLog], options: TrainOptions,
                 progress: Callable[[str], None], trainer: Callable[..., Any] | None
                 ) -> tuple[NetworkFit, list[Any]]:
    """How `fit_candidates` trains a network, and the stages any network is trained in
    (none where none is). The model file holds the network alone even where no signal may
    be read from it: untrained there, it costs nothing (its training is most of `train`'s
    time)."""
    from models.training import DEFAULT_STAGES, Stage, TrainingLog, train

    stages = [Stage(s.horizon_steps, max(1, round(s.iterations * options.iterations_scale)),
                    s.learning_rate) for s in DEFAULT_STAGES]
    sequences = [TrainingLog(t.name, t.commands, t.sensors) for t in training]
    alone = network_asked(options.predictors)
    if not alone:
        progress("the network alone is not trained: no signal may be read from it "
                 f"(--predictor {', '.join(options.predictors)})")

    on_linear = "network-on-linear" in options.predictors
    runs = max(1, int(alone) + int(on_linear))

    def fit_network(linear: np.ndarray | None) -> Any:
        trained = alone or linear is not None
        return (trainer or train)(sequences, hidden=options.hidden,
                                  stages=stages if trained else [],
                                  seed=options.seed, progress=progress, linear=linear,
                                  run=(runs if linear is not None else 1, runs))

    return fit_network, stages if alone or on_linear else []


def _save(output: Path, fitted: Candidates, metadata: dict[str, Any], profile: Profile,
          logs: tuple[Sequence[Path], Sequence[Path]], options: "TrainOptions",
          progress: Callable[[str], None]) -> list[str]:
    """Write the model, then add what needs it: the change test's largest statistics on the
    logs (trained on, held out) it learnt from (`training_change`), which calibrate counts
    beside its own logs, and the g thresholds the held-out logs raise
    (`heldout_thresholds`). Returns those raised."""
    from models.store import load_model, save_model, write_model

    save_model(output, fitted.network, fitted.normaliser, metadata, fitted.extra)
    model = load_model(output)
    model.update_entries(change_training=training_change_peaks(
        model, profile, [*logs[0], *logs[1]], options.healthy, progress))
    if logs[1]:
        progress(f"g on the {len(logs[1])} held-out log(s)")
    thresholds = heldout_thresholds(model, profile, logs[1], options.healthy)
    model.update_entries(thresholds=thresholds)
    write_model(model, output)
    return raised(profile.thresholds, thresholds)


def _learn_beside_the_model(read: Sequence[ReadLog], read_heldout: Sequence[ReadLog],
                            training: Sequence[ScoringLog], profile: Profile
                            ) -> tuple[Relations | Refused, StartReference]:
    """The command relations and the start state (or why there are none). ``training`` is
    what the network trained on (a single log's first part)."""
    relations = learn_relations([r.relation for r in read], [r.relation for r in read_heldout],
                                profile)
    actuators = len(profile.commands)     # the logs' model drive ends with measured inputs
    start_state = learn_start_state(
        [start_reading(t.commands[:, :actuators], t.sensors, profile.dt_s) for t in training],
        [start_reading(r.scoring.commands[:, :actuators], r.scoring.sensors, profile.dt_s)
         for r in read_heldout], [profile.full_scales[n] for n in profile.sensor_names])
    return relations, start_state


def _fit_ahead(training: Sequence[ScoringLog], heldout: Sequence[ScoringLog], whole: bool,
               profile: Profile, progress: Callable[[str], None]) -> dict[str, Any]:
    """model.json's `ahead_predictor`: the change test's predictor a moment ahead, or why
    there is none. With ``whole`` held-out logs it is fitted to them too, its skill measured
    log by log from fits to the others; else (the tail of a single log held out) on it."""
    commands = len(profile.commands)     # the logs' model drive ends with measured inputs

    def ahead_log(log: ScoringLog) -> AheadLog:
        return AheadLog(log.commands[:, :commands], log.sensors,
                        log.commands[:, commands:] if profile.inputs else None, log.cuts)

    fitted = [ahead_log(t) for t in training]
    held = [ahead_log(t) for t in heldout]
    ahead = (fit_ahead([*fitted, *held], profile.sensor_names, profile.dt_s) if whole
             else fit_ahead(fitted, profile.sensor_names, profile.dt_s, held))
    if ahead is None:
        return {"refused": "too few complete samples to fit it"}
    progress("the change test's predictor a moment ahead, skill on logs left out of its fit: "
             + ", ".join(f"{name} {skill:.2f}" for name, skill in ahead.skill.items()))
    return ahead.to_json()


def _complete_steps(log: ScoringLog) -> int:
    return int(np.isfinite(log.sensors).all(axis=1).sum())


def _input_entries(profile: Profile, training: Sequence[ScoringLog]) -> list[dict[str, Any]]:
    """Each measured input, with its median on the training logs (what a simulated mission,
    a DMS or the pattern table's faults, holds it at) and whether any of them fed it (moved
    it): one no log fed, the model never learnt how it acts."""
    actuators = len(profile.commands)
    values = np.concatenate([t.commands[:, actuators:] for t in training])
    return [{"name": i.name, "unit": i.unit, "typical": round(float(np.median(values[:, k])), 6),
             "fed": any(np.nanmax(column) > np.nanmin(column) for t in training
                        if np.isfinite(column := t.commands[:, actuators + k]).any())}
            for k, i in enumerate(profile.inputs)]


def _where(profile: Profile) -> str:
    """Where the profile came from, as commands given only --model find it again: a
    built-in name, or its file's absolute path."""
    where = profile.source_path
    return where if where.startswith("builtin:") else str(Path(where).resolve())


def _metadata(output: Path, profile: Profile, training_paths: Sequence[Path],
              training: Sequence[ScoringLog], heldout: Sequence[ScoringLog],
              result: TrainingResult, stages: Sequence[Any], seed: int) -> dict[str, Any]:
    digests = [{"log": p.name, "sha256": log_digest(p)} for p in training_paths]
    return {
        "name": output.name,
        "vehicle": profile.name,
        "profile": _where(profile),
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "tool_version": __version__,
        "dt_s": profile.dt_s,
        "signals": {
            "commands": list(profile.command_names),
            "inputs": _input_entries(profile, training),
            "sensors": [{"name": s.name, "unit": s.unit} for s in profile.sensors],
        },
        "full_scale": profile.full_scales,
        "window_samples": profile.window_samples,
        "thresholds": profile.thresholds,
        "trained_on": {
            "vehicle": profile.name,
            "logs": len(training_paths),
            "operating_hours": round(result.operating_hours, 4),
            "heldout_hours": round(sum(_complete_steps(h) for h in heldout)
                                   * profile.dt_s / 3600, 4),
            "heldout": result.heldout_split,
            "model_rate_hz": round(1 / profile.dt_s, 6),
            "logged_rates_hz": result.logged_rates_hz,
        },
        **skill_metadata(result.scores, result.chosen, [h.name for h in heldout], profile),
        "training": {
            "data_sha256": hashlib.sha256(
                "".join(d["sha256"] for d in digests).encode()).hexdigest(),
            "logs": digests,
            "steps": sum(len(t.commands) for t in training),
            "stages": [s.__dict__ for s in stages],
            "seed": seed,
        },
    }


def score_model(model: "LoadedModel", profile: Profile, logs: Sequence[Path],
                horizon_s: float | None, progress: Callable[[str], None] = lambda _: None
                ) -> tuple[list[HorizonScore], HorizonScore]:
    """Measure an existing model's skill on normal ``logs`` it was not trained on and record
    it (with the horizon chosen) in the model's entries (not yet written). Without the
    training data, the mean and linear yardsticks are fitted on these logs themselves,
    which favours them: the skill found is, if anything, too low."""
    from auvdiag_cli.engine.diagnosis import check_model_fits

    for log in logs:
        check_model_fits(model, profile, log)
    seen = [p.name for p in logs if log_digest(p) in model.card.training_digests]
    if seen:
        raise UsageError(f"the model was trained on {', '.join(seen)}: score it on normal logs "
                         "it has not seen")
    typical = {i.name: i.typical for i in model.card.inputs}
    unlearnt = [i.name for i in model.card.inputs if not i.fed]
    scoring = [scoring_log(p, profile, progress, typical, unlearnt) for p in logs]
    scores = [replace(score, predictors=model.predictors) for score in assess(
        model.dynamics, np.asarray(model.normaliser.command_scale),
        np.asarray(model.normaliser.state_scale), scoring, scoring, profile.sensor_names,
        profile.dt_s, horizon_candidates(profile, horizon_s))]
    chosen = choose_horizon(scores)
    model.update_entries(**skill_metadata(scores, chosen, [p.name for p in logs], profile))
    return scores, chosen
