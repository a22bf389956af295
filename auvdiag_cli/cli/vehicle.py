"""`simulate`, `scenarios`, `inspect`, `init-profile` and `derive-table`: the vehicle, its
logs and its pattern table."""

from pathlib import Path
from typing import Annotated

import typer

from auvdiag_cli.cli.app import (
    EXIT_FAULT,
    EXIT_NORMAL,
    EXIT_UNUSABLE,
    ModelOption,
    ModelProfileOption,
    ProfileOption,
    app,
    fail,
    user_errors,
)
from auvdiag_errors import UsageError


@app.command()
def simulate(
    scenario: Annotated[str, typer.Argument(help="Scenario name (see 'auvdiag scenarios').")],
    output: Annotated[Path, typer.Option("--output", "-o", help="Log path to write.")],
    log_format: Annotated[str, typer.Option(
        "--format", help="Log format: bag (ROS 1), db3 (ROS 2, sqlite3), ros2-mcap (ROS 2, "
                         "mcap storage), mcap (standalone), json-mcap (standalone, JSON "
                         "messages), protobuf-mcap (standalone, Protocol Buffers messages), "
                         "tlog (MAVLink), bin (DataFlash), ulog (PX4), alog (MOOS-IvP "
                         "pLogger), csv (the profile's "
                         "[sources.csv] columns), topic-csv (one CSV per ROS topic)."
    )] = "ros2-mcap",
    seed: Annotated[int, typer.Option(help="Noise seed.")] = 0,
    fault_at: Annotated[float | None, typer.Option(
        help="Move the scenario's fault onset to this time (s).")] = None,
    start: Annotated[str, typer.Option(
        help="When the log's clock starts (ISO 8601, UTC if no zone).")
    ] = "2026-11-22T10:00:00Z",
    namespace: Annotated[str, typer.Option(
        help="ROS namespace the vehicle publishes under (/rov2: /rov2/thrusters/command); "
             "ROS formats only.")] = "",
    profile: ProfileOption = None,
) -> None:
    """Simulate a dive of the profile's vehicle and write it as a log with its ground truth.

    The vehicle is flown with the physics of the profile's [simulation] table and logged the
    way its [sources] tables describe. The truth goes to NAME.truth.json (scenario, fault,
    onset) and NAME.truth.csv (true velocities, heading, position and depth at 10 Hz); a
    mission's plan to NAME.mission.json."""
    from auvdiag_cli import api
    from auvdiag_cli.simulator.truth_files import truth_paths
    from auvdiag_cli.simulator.writers import LOG_FORMATS

    if log_format not in LOG_FORMATS:
        fail(f"unknown --format {log_format!r} (choose from {', '.join(LOG_FORMATS)})")
    with user_errors(output):
        dive = api.simulate(scenario, api.load_profile(profile), output, log_format=log_format,
                            seed=seed, fault_at_s=fault_at, start_ns=_unix_ns(start),
                            namespace=namespace)
    typer.echo(f"wrote {output} ({log_format}, {dive.duration_s:.1f} s) and "
               f"{truth_paths(output)[0].name}")


@app.command()
def inspect(
    log: Annotated[Path, typer.Argument(help="Log of any supported format.")],
    profile: ProfileOption = None,
) -> None:
    """Show what a log holds and, with --profile, which of the profile's signals resolve in it.

    Lists the format, time span, topics or message types with their types, counts and rates,
    and with --profile for each of its signals whether it resolved (or why not, with the
    closest topics). Exit status 0 when the log reads (with --profile: when every signal
    resolves), 2 otherwise (also when the log holds none of them, or the profile has no
    mapping for its format: the listing still shows what the log holds)."""
    from auvdiag_cli import api
    from auvdiag_cli.reports.text import inspection_lines

    with user_errors(log):
        result = api.inspect(log, None if profile is None else api.load_profile(profile))
    for line in inspection_lines(result):
        typer.echo(line)
    if not result.usable:
        raise typer.Exit(EXIT_UNUSABLE)


def _unix_ns(text: str) -> int:
    from datetime import UTC, datetime

    try:
        moment = datetime.fromisoformat(text)
    except ValueError:
        fail(f"--start {text!r} is not an ISO 8601 time (e.g. 2026-11-22T10:00:00Z)")
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=UTC)
    return round(moment.timestamp() * 1e9)


@app.command("init-profile")
def init_profile(
    log: Annotated[Path, typer.Argument(help="A log of the vehicle, of any supported format.")],
    output: Annotated[Path | None, typer.Option(
        "--output", "-o", help="Profile file to write (default: print it).", dir_okay=False)
    ] = None,
    name: Annotated[str | None, typer.Option(
        help="The vehicle's name (default: the log's name).")] = None,
    like: Annotated[Path | None, typer.Option(
        "--like", help="Start from this profile (a file, or a built-in one such as "
                       "bluerov2_standard) and fit its mapping to the log.", dir_okay=False)
    ] = None,
    closed_loop: Annotated[bool, typer.Option(
        "--closed-loop", help="Draft a model of the closed loop from an ArduPilot DataFlash "
                              "or telemetry log or a PX4 ULog: the controller's set points "
                              "(ATT DesRoll, DesPitch; RATE RDes, PDes, YDes; CTUN DCRt; "
                              "NAV_CONTROLLER_OUTPUT nav_roll, nav_pitch; PX4's "
                              "vehicle_rates_setpoint, vehicle_local_position_setpoint "
                              "velocities, tecs_status height rate and airspeed) drive the "
                              "model, what was measured beside each is a sensor, the motor "
                              "outputs are read for the effort check only. A log whose set "
                              "points are named commanded, desired or target is drafted so "
                              "without it.")] = False,
) -> None:
    """Write a starting vehicle profile from what a log holds.

    Proposes as commands the motor outputs, thrust or PWM fields and as sensors the gyro
    rates, climb or depth rates and velocities that are in the log and vary there, the
    log's armed flag as operating time, and for CSV the clock column. What a log cannot
    tell (units, full scales, components, thresholds, the pattern table) is marked CHECK.
    With --like, the draft is that profile with each signal that does not read on the log
    moved to the closest field that does (each move listed at the top). The draft loads and
    resolves on the log it came from: `auvdiag inspect LOG --profile FILE` shows it."""
    from auvdiag_cli import api

    with user_errors(log):
        api.log_format(log)
        text = api.draft_profile(log, name, like, closed_loop)
        if output is None:
            typer.echo(text, nl=False)
            return
        if output.exists():
            raise UsageError(f"{output}: exists already, not overwriting")
        output.write_text(text, encoding="utf-8")
    typer.echo(f"profile written to {output}; check the lines marked CHECK, then:\n"
               f"  auvdiag inspect {log} --profile {output}")


@app.command("derive-table")
def derive_table(
    model: ModelOption = None,
    profile: ModelProfileOption = None,
    json_path: Annotated[Path | None, typer.Option(
        "--json", help="Also write the signatures and the table as JSON.", dir_okay=False)
    ] = None,
    log: Annotated[Path | None, typer.Option(
        "--log", help="A normal log of the vehicle: the faults are replayed open loop on its "
                      "commands instead of on a mission flown by the profile's controller.")
    ] = None,
) -> None:
    """Derive the pattern table by simulating every single-component fault on the model.

    Each thruster producing nothing and each sensor reading zero is simulated with the
    dynamics model as the vehicle, on every DMS and on a mission: flown by the profile's
    controller, or open loop on the commands of --log, or (a profile without a controller
    and no --log) on the DMSs played one after another. The b signatures are printed, and
    the table they imply is compared with the profile's. Exit status 0 when they agree, 1
    when they differ."""
    from auvdiag_cli import api
    from auvdiag_cli.files import write_json
    from auvdiag_cli.reports.derivation import derivation_lines

    with user_errors(log or model or "builtin model"):
        loaded_profile = api.load_profile(profile, model=model)
        result = api.derive_table(log, loaded_profile, api.load_model(model, loaded_profile))
    for line in derivation_lines(result, loaded_profile.sensor_names):
        typer.echo(line)
    if json_path is not None:
        write_json({"signatures": [s.__dict__ for s in result.signatures],
                    "table": [r.__dict__ for r in result.rows],
                    "matches_profile": result.matches_profile}, json_path)
    raise typer.Exit(EXIT_NORMAL if result.matches_profile else EXIT_FAULT)


@app.command()
def scenarios(profile: ProfileOption = None) -> None:
    """List the simulator's named scenarios for the profile's vehicle."""
    from auvdiag_cli import api

    with user_errors(profile or "builtin profile"):
        known = api.scenarios(api.load_profile(profile))
    width = max(len(name) for name in known)
    for name, scenario in known.items():
        typer.echo(f"{name:<{width}}  {scenario.description}")


