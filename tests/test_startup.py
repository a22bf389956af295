"""No alarm from the replay's start-up: logs that begin with the vehicle already moving, in a
turn, or with a sensor offset, on the Twin-Burger and on two other twin-thruster vehicles
(one heavier, with less drag, stronger thrusters and a slower, noisier gyro; one lighter,
with more drag, weaker and slower thrusters and a slower, noisier flow sensor), each with a
model trained by `auvdiag train` on that vehicle's own normal logs and calibrated on
others."""

import json
import re
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from auvdiag_cli.vehicle.profile import profile_text

pytestmark = pytest.mark.slow    # trains models or simulates fleets

runner = CliRunner()
VARIANTS = {
    "heavy_twin": [("inertia = 80.0", "inertia = 130.0"),
                   ("linear_drag = 20.0", "linear_drag = 14.0"),
                   ("max_thrust_n = 15.0", "max_thrust_n = 21.0"),
                   ("rate_hz = 50.0", "rate_hz = 20.0"), ("noise = 0.008", "noise = 0.015")],
    "light_twin": [("inertia = 80.0", "inertia = 55.0"),
                   ("quadratic_drag = 80.0", "quadratic_drag = 110.0"),
                   ("max_thrust_n = 15.0", "max_thrust_n = 12.0"), ("lag_s = 0.2", "lag_s = 0.4"),
                   ("rate_hz = 10.0", "rate_hz = 5.0"), ("noise = 0.004", "noise = 0.008")],
}
TRAINING_SCENARIOS = ["paper-normal", "mission-ccw", "mission-large-cw", "mission-large-ccw",
                      "mission-sprint-cw", "dms-za", "dms-zb", "dms-zc", "excitation"]


def _simulate(scenario: str, seed: int, target: Path, profile: str) -> Path:
    """The dive of that seed, on a day of its own (normal dives of several days)."""
    result = runner.invoke(app, ["simulate", scenario, "--seed", str(seed), "--format", "csv",
                                 "--profile", profile, "--output", str(target),
                                 "--start", f"2026-10-{seed:02d}T10:00:00"])
    assert result.exit_code == 0, result.output
    return target


@pytest.fixture(scope="module", params=["twin_burger", *VARIANTS])
def vehicle(request, tmp_path_factory) -> tuple[str, list[str]]:
    """Profile and model options: the Twin-Burger with its shipped model, or a variant with
    a model trained and calibrated here."""
    if request.param == "twin_burger":
        return "twin_burger", []
    work = tmp_path_factory.mktemp(request.param)
    text, _ = profile_text(None)
    for old, new in [*VARIANTS[request.param],
                     ('name = "twin-burger"', f'name = "{request.param}"')]:
        assert old in text, old
        text = text.replace(old, new)
    profile = work / f"{request.param}.toml"
    profile.write_text(re.sub(r"(?m)^horizon_s = .*$", 'horizon_s = "auto"', text))
    logs = [str(_simulate(s, seed, work / f"{s}-{seed}.csv", str(profile)))
            for s in TRAINING_SCENARIOS for seed in (1, 2)]
    held = [str(_simulate(s, 9, work / f"held-{s}.csv", str(profile)))
            for s in ("mission-ccw", "paper-normal")]
    model = work / "model"
    trained = runner.invoke(app, ["train", *logs, *[a for h in held for a in ("--holdout", h)],
                                  "--profile", str(profile), "--output", str(model),
                                  # the least-squares predictors alone (the network is
                                  # then not trained): the start-up is the replay's
                                  # whichever predictor it reads, and the Twin-Burger's
                                  # shipped model reads the network
                                  "--predictor", "linear", "--predictor", "linear-replay"])
    assert trained.exit_code == 0, trained.output
    relations = json.loads((model / "model.json").read_text())["command_relations"]
    assert all(t is not None for t in relations["thresholds"]), trained.output
    # The open-loop logs teach nothing about how the commands follow the motion: the DMS
    # runs are marked as such, the excitation runs are found by how far they depart. How
    # the motion answers the thrusts they teach as well as any.
    fitted = relations["fitted_on"]
    assert {"excitation-1.csv", "excitation-2.csv"} <= set(
        fitted["logs"] if relations.get("form") == "thrust" else fitted["open_loop_left_out"])
    assert not any(name.startswith("dms-") for name in relations["fitted_on"]["logs"])
    # As for any new vehicle: thresholds from normal dives the model has not seen.
    normal = [str(_simulate(s, seed, work / f"calibration-{s}-{seed}.csv", str(profile)))
              for s in ("paper-normal", "mission-ccw", "mission-large-cw") for seed in (5, 6)]
    calibrated = runner.invoke(app, ["calibrate", *normal, "--model", str(model),
                                     "--profile", str(profile)])
    assert calibrated.exit_code == 0 and "warning" not in calibrated.output, calibrated.output
    return str(profile), ["--model", str(model)]


def _starting_late(log: Path, start_s: float, target: Path) -> Path:
    table = pd.read_csv(log)
    table = table[table["time_s"] >= table["time_s"].min() + start_s]
    table.to_csv(target, index=False)
    return target


def _with_offset(log: Path, target: Path) -> Path:
    table = pd.read_csv(log)
    table["flow_mps"] += 0.02           # 4 % of full scale, a zero error within tolerance
    table["yaw_rate_rps"] += 0.01
    table.to_csv(target, index=False)
    return target


def _turning_time(truth: Path) -> float:
    frame = pd.read_csv(truth)
    turning = frame[(frame["t_s"] > 30) & (frame["yaw_rate_rps"].abs() > 0.15)]
    return float(turning["t_s"].iloc[0]) + 1.0


@pytest.fixture(scope="module")
def dive(vehicle, tmp_path_factory) -> Path:
    """The vehicle's normal dive the starts are cut from (its truth beside it)."""
    return _simulate("paper-normal", 31, tmp_path_factory.mktemp("dive") / "dive.csv",
                     vehicle[0])


@pytest.mark.parametrize("start", ["moving", "turning", "offset"])
def test_no_alarm_from_the_start_of_a_log(vehicle, dive, tmp_path, start):
    profile, model_options = vehicle
    log = dive
    if start == "moving":
        log = _starting_late(log, 40.0, tmp_path / "moving.csv")
    elif start == "turning":
        when = _turning_time(dive.with_suffix(".truth.csv"))
        log = _starting_late(log, when, tmp_path / "turning.csv")
    else:
        log = _with_offset(log, tmp_path / "offset.csv")
    result = runner.invoke(app, ["diagnose", str(log), "--profile", profile, *model_options,
                                 "--json", "-", "--quiet"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["verdict"] == "normal" and not report["not_judged"]
    if start == "offset":       # a steady offset stays in the residual: no margin to spare
        return
    for segment in report["segments"]:
        for name, g in segment["max_g"].items():
            assert g < 0.8 * segment["thresholds"][name], (segment, name)
