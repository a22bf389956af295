"""`train`, `score`, `relate` and `calibrate`: making a model and its thresholds."""

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from auvdiag_cli.cli.app import (
    EXIT_FAULT,
    CopyOutputOption,
    HealthyOption,
    HoldoutOption,
    HorizonOption,
    ModelProfileOption,
    ModelToUpdateOption,
    ProfileOption,
    app,
    horizon_option,
    log_paths,
    report_progress,
    user_errors,
)
from auvdiag_errors import UsageError

if TYPE_CHECKING:
    from auvdiag_cli.jobs.healthy import HealthyParts

PredictorOption = Annotated[list[str] | None, typer.Option(
    "--predictor", help="A predictor each signal may be read from: linear, linear-replay, "
                        "network, network-on-linear (repeatable; default: all four, the best "
                        "per signal on the held-out data). With linear and without network, "
                        "the network is not trained: far quicker.")]


def healthy_parts(path: Path | None) -> "HealthyParts":
    from auvdiag_cli import api

    return api.HealthyParts() if path is None else api.read_healthy_parts(path)


@app.command()
def train(
    logs: Annotated[list[Path], typer.Argument(
        help="Normal-condition logs to learn from, or folders of them (logs in which the "
             "vehicle never operates are left out).")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Model directory to write.",
                                         file_okay=False)],
    profile: ProfileOption = None,
    holdout: HoldoutOption = None,
    horizon: HorizonOption = None,
    keep_unskilled: Annotated[bool, typer.Option(
        "--keep-unskilled", help="Write the model even when no signal has skill (its "
                                 "diagnoses will judge nothing).")] = False,
    hidden: Annotated[int, typer.Option(help="Size of the recurrent context.", min=4)] = 32,
    seed: Annotated[int, typer.Option(help="Random seed of the training.")] = 0,
    iterations_scale: Annotated[float, typer.Option(
        help="Multiply every stage's iteration count (e.g. 0.1 for a quick model).",
        min=0.001)] = 1.0,
    predictor: PredictorOption = None,
    healthy: HealthyOption = None,
) -> None:
    """Train the healthy-vehicle dynamics model on normal logs and write a model directory.

    Four predictors are fitted: a least-squares linear model, the same linear model refined
    against the error of free replays of the training logs (linear-replay), the recurrent
    network (trained in stages, short rollouts first and long free-running ones after), and
    the network on top of the least-squares model. Each signal is read from the one with the
    best skill on held-out normal data, against naive predictors (the last value holds, the
    mean): a signal that none predicts better is never judged.
    It also learns how the commands follow the motion (see 'auvdiag relate') and, for the
    profile's groups of actuators that act alike ([[effort]]), each actuator's normal share
    of their effort, judged on later logs against a false-alarm budget of 1 % of normal logs
    (needs three normal logs with steady operation; logs of more than one day, since logs
    that differ no more than their own noise cannot show how far another day's strays:
    the training report then says so). Exit status 1 when nothing can be judged (no model
    is written unless --keep-unskilled)."""
    from auvdiag_cli import api
    from auvdiag_cli.jobs.skill_record import paper_model_error
    from auvdiag_cli.reports.training import training_lines
    from models.fast import PREDICTOR_KINDS

    with user_errors(output):
        unknown = [p for p in predictor or () if p not in PREDICTOR_KINDS]
        if unknown:
            raise UsageError(f"unknown predictor {', '.join(unknown)} (known: "
                             f"{', '.join(PREDICTOR_KINDS)})")
        vehicle = api.load_profile(profile)
        options = api.TrainOptions(
            tuple(log_paths(holdout or [])), hidden, seed, iterations_scale,
            horizon_option(horizon, vehicle.horizon_s), keep_unskilled,
            tuple(predictor or PREDICTOR_KINDS), healthy_parts(healthy))
        result = api.train(logs, vehicle, output, options=options, progress=report_progress)
    for line in training_lines(result, paper_model_error(vehicle), vehicle):
        typer.echo(line)
    if not result.judges_anything:
        typer.echo("auvdiag: no signal has skill, or enough held-out data to show it, and no "
                   "actuator's commands or share of the effort can be judged (see above)"
                   + ("" if result.written else "; the model is not written (--keep-unskilled "
                                                "writes it anyway)"), err=True)
        raise typer.Exit(EXIT_FAULT)


@app.command()
def score(
    logs: Annotated[list[Path], typer.Argument(help="Normal logs the model was not trained on.")],
    model: ModelToUpdateOption,
    horizon: HorizonOption = None,
    output: CopyOutputOption = None,
    profile: ModelProfileOption = None,
) -> None:
    """Measure an existing model's skill per signal on normal logs and record it.

    For models trained before skill was measured, or to re-check a model on new dives: the
    skill and prediction horizon found replace those in model.json, and signals without
    skill are no longer judged. Exit status 1 when no signal has skill."""
    from auvdiag_cli import api
    from auvdiag_cli.engine.judging import own_log_only
    from auvdiag_cli.reports.training import skill_lines

    with user_errors(model):
        vehicle = api.load_profile(profile, model=model)
        loaded = api.load_model(model, vehicle)
        scores, chosen = api.score(logs, vehicle, loaded,
                                   horizon_s=horizon_option(horizon, vehicle.horizon_s),
                                   progress=report_progress)
        api.save_model(loaded, output or model)
    for line in skill_lines(scores, chosen, own_log_only(vehicle)):
        typer.echo(line)
    typer.echo(f"skill written to {(output or model) / 'model.json'}")
    if not chosen.judged:
        raise typer.Exit(EXIT_FAULT)


@app.command()
def relate(
    logs: Annotated[list[Path], typer.Argument(help="Normal logs to learn from.")],
    model: ModelToUpdateOption,
    holdout: HoldoutOption = None,
    output: CopyOutputOption = None,
    profile: ModelProfileOption = None,
) -> None:
    """Learn how the vehicle's commands follow its motion, and where its logs start.

    A controller holding heading, depth or attitude hides a weakened thruster from the
    motion by driving it harder; the commands then depart from what the motion needs. This
    learns that relation from normal logs (DMS runs are left out) both ways: each command
    from the motion (open-loop logs left out), and the motion from each actuator's thrust;
    it keeps the one that judges the smaller loss of thrust, says which and why, and sets
    per actuator how much extra effort (or thrust lost) normal logs reach. It also records where the
    normal logs recorded from rest start, so that a sensor wrong from the first sample is
    found. 'auvdiag train' does both itself; use this command for a model trained before,
    or to learn from other dives. What cannot be learned keeps what the model had."""
    from auvdiag_cli import api
    from auvdiag_cli.reports.training import relation_lines, start_lines

    with user_errors(model):
        vehicle = api.load_profile(profile, model=model)
        loaded = api.load_model(model, vehicle)
        relations, start = api.relate(logs, vehicle, loaded, holdout=holdout or (),
                                      progress=report_progress)
        relations_refused = isinstance(relations, api.Refused)
        if not relations_refused or start.refused is None:
            api.save_model(loaded, output or model)
    for line in [*relation_lines(relations, vehicle.command_names, vehicle.effort_groups),
                 *start_lines(start, vehicle.sensor_names)]:
        typer.echo(line)
    if relations_refused and start.refused is not None:
        typer.echo("auvdiag: nothing learned; the model is left as it was", err=True)
        raise typer.Exit(EXIT_FAULT)
    typer.echo(f"written to {(output or model) / 'model.json'}")
    if relations_refused:
        raise typer.Exit(EXIT_FAULT)


@app.command()
def calibrate(
    logs: Annotated[list[Path], typer.Argument(
        help="Normal-condition logs, or folders of them (logs in which the vehicle never "
             "operates are left out).")],
    model: ModelToUpdateOption,
    faulty: Annotated[list[Path] | None, typer.Option(
        "--faulty", help="A log with a known fault, to check detection (repeatable).")
    ] = None,
    margin: Annotated[float, typer.Option(help="Threshold = margin x largest normal g.")
                      ] = 1.5,
    output: CopyOutputOption = None,
    profile: ModelProfileOption = None,
    floor_at_profile: Annotated[bool, typer.Option(
        "--floor-at-profile", help="Never set a threshold below the profile's for its mode "
                                   "(for few calibration logs, or signals a DMS hardly moves)."
    )] = False,
    false_alarm_rate: Annotated[str | None, typer.Option(
        "--false-alarm-rate", metavar="RATE",
        help="Set every threshold for this false-alarm rate instead of the margin rule: a "
             "share of normal logs (0.05) or alarms per hour of operation (0.5/h).")] = None,
    healthy: HealthyOption = None,
) -> None:
    """Set the model's thresholds from the g it reaches on normal logs.

    Per diagnosis mode (mission, ZA, ZB, ZC) and signal: threshold = margin x the largest g
    on the normal logs (zero false alarms there by construction; the implied rate is stated
    as a 95 % upper bound). Modes with under 30 s of data keep the profile's
    thresholds, raised where these logs need it.
    With --faulty, those logs are diagnosed with the new thresholds to show the margin.
    With --false-alarm-rate R, each judge (a judged signal's g in a mode, a sensor's start,
    an actuator's commands against the motion) gets an equal share of R, and its threshold
    is where a distribution fitted to its normal values reaches that share (an extreme-value
    law for per-log peaks), so that it extrapolates beyond the largest value seen; each
    log is then judged with the thresholds fitted on the others, and the count reported.
    Judges with fewer than 5 logs keep the margin rule (for the change test never below a
    window |z| of 6 and a sum of 8; a fitted law may go as low as 4 and 4). The change
    test (each log against its own beginning) counts the logs the model was trained on
    too (train keeps their largest values in the model), and leaves out of a threshold one
    log whose
    largest value there is twice every other log's (with 5 logs or more), and names it:
    check it for a failure.
    Where the profile groups actuators that act alike ([[effort]]), the normal effort
    shares are refitted with these logs added (learnt from them if the model has none),
    their thresholds set for their share of R (default: the model's budget)."""
    from auvdiag_cli import api
    from auvdiag_cli.reports.training import calibration_lines

    with user_errors(model):
        budget = (None if false_alarm_rate is None
                  else api.FalseAlarmBudget.parse(false_alarm_rate))
        vehicle = api.load_profile(profile, model=model)
        loaded = api.load_model(model, vehicle)
        result = api.calibrate(logs, vehicle, loaded, faulty_logs=faulty or (),
                               options=api.CalibrateOptions(margin, budget, floor_at_profile,
                                                            healthy_parts(healthy)),
                               progress=report_progress)
        api.save_model(loaded, output or model)
    for line in calibration_lines(result):
        typer.echo(line)
    typer.echo(f"thresholds written to {(output or model) / 'model.json'}")


