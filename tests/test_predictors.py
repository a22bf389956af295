"""Model choice by validation: the linear model (least squares, and refined against the
replay's error), the network and the network on top of the linear model, each signal read
from the one with the best held-out skill; the replay of a model that mixes them, free and
one step at a time, and on every engine."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from auvdiag_cli.cli import app
from models.dynamics import RecurrentDynamics
from models.fast import ChosenDynamics, FastDynamics, FastStepper, linear_only
from models.normaliser import Normaliser
from models.store import load_model

pytestmark = pytest.mark.slow    # trains models or simulates fleets

runner = CliRunner()


def write_linear_vehicle(path: Path, seed: int, seconds: float = 240.0,
                         idle: bool = False, noise: float = 0.01) -> Path:
    """A CSV log of a vehicle whose speed is a first-order lag of its command (exactly what
    a linear model describes), with the command stepping every few seconds; ``idle``: the
    command stays at neutral (a log recorded on deck); ``noise``: the speed sensor's (rms)."""
    rng = np.random.default_rng(seed)
    dt = 0.1
    steps = round(seconds / dt)
    levels = np.repeat(rng.uniform(-1, 1, steps // 30 + 1), 30)[:steps] * (not idle)
    speed = np.zeros(steps)
    for k in range(1, steps):
        speed[k] = speed[k - 1] + dt * (0.8 * levels[k - 1] - speed[k - 1]) / 2.0
    measured = speed + rng.normal(0, noise, steps)
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["t", "cmd", "speed"])
        for k in range(steps):
            writer.writerow([f"{k * dt:.3f}", f"{levels[k]:.4f}", f"{measured[k]:.5f}"])
    return path


PROFILE = """
[vehicle]
name = "lagged"
description = "a vehicle whose speed lags its command"
dt_s = 0.1

[[commands]]
name = "cmd"
component = "thruster"
description = "the thruster command"

[[sensors]]
name = "speed"
component = "speed_sensor"
unit = "m/s"
full_scale = 1.0
description = "speed"

[operating]
idle_after_s = 1.0

[matching]
window_samples = 20
decision_window_s = 3.0

[thresholds.mission]
speed = 15.0

[[pattern]]
case = 0
b = { speed = 0 }
components = []

[sources.csv]
time = { column = "t", unit = "s" }

[sources.csv.signals]
cmd = { column = "cmd" }
speed = { column = "speed" }
"""


@pytest.fixture(scope="module")
def lagged(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    folder = tmp_path_factory.mktemp("lagged")
    profile = folder / "lagged.toml"
    profile.write_text(PROFILE)
    logs = [write_linear_vehicle(folder / f"run_{seed}.csv", seed) for seed in range(4)]
    output = folder / "model"
    result = runner.invoke(app, ["train", *map(str, logs[:3]), "--holdout", str(logs[3]),
                                 "--profile", str(profile), "-o", str(output),
                                 "--iterations-scale", "0.03", "--hidden", "8"])
    assert result.exit_code == 0, result.output
    return profile, output, folder


def test_a_linear_vehicle_is_read_from_the_linear_model(lagged: tuple[Path, Path, Path]):
    profile, output, folder = lagged
    meta = json.loads((output / "model.json").read_text())
    assert meta["predictors"]["per_signal"] == {"speed": "linear"}
    assert meta["skill"]["signals"]["speed"]["skill"] > 0.8
    model = load_model(output)
    assert model.predictors == {"speed": "linear"}
    assert {"linear"} | {k for k in model.extra if k.startswith("on_linear/")} <= set(
        model.extra)
    # The diagnosis reads the signal from it and says so.
    log = write_linear_vehicle(folder / "later.csv", 9, seconds=120.0)
    report = folder / "later.json"
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(profile), "--model",
                                 str(output), "--json", str(report)])
    assert result.exit_code == 0, result.output
    assert json.loads(report.read_text())["model"]["predictors"] == {"speed": "linear"}


def test_a_noisy_sensor_is_read_from_the_linear_model_fitted_to_the_replay(tmp_path: Path):
    """Sensor noise biases a one-step least-squares fit (the noise in x(k) is in the change
    x(k+1) - x(k) too): its replay decays too fast. Refined against the replay's error, the
    same linear model replays the noisy speed as it is."""
    profile = tmp_path / "lagged.toml"
    profile.write_text(PROFILE)
    logs = [write_linear_vehicle(tmp_path / f"run_{seed}.csv", seed, noise=0.15)
            for seed in range(4)]
    output = tmp_path / "model"
    result = runner.invoke(app, ["train", *map(str, logs[:3]), "--holdout", str(logs[3]),
                                 "--profile", str(profile), "-o", str(output),
                                 "--iterations-scale", "0.02", "--hidden", "8",
                                 "--predictor", "linear", "--predictor", "linear-replay"])
    assert result.exit_code == 0, result.output
    # No signal may be read from the network alone: it is not trained (most of the time
    # `train` takes), only held in the model file.
    assert "the network alone is not trained" in result.output
    assert "stage 1/" not in result.output
    assert json.loads((output / "model.json").read_text())["training"]["stages"] == []
    signal = json.loads((output / "model.json").read_text())["skill"]["signals"]["speed"]
    assert json.loads((output / "model.json").read_text())["predictors"]["per_signal"] == {
        "speed": "linear-replay"}
    assert signal["versus_linear"] > 0.2      # against the least-squares fit it started from
    model = load_model(output)
    assert model.predictors == {"speed": "linear-replay"} and "linear_replay" in model.extra
    log = write_linear_vehicle(tmp_path / "later.csv", 9, seconds=120.0, noise=0.15)
    report = tmp_path / "later.json"
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(profile), "--model",
                                 str(output), "--json", str(report)])
    # Exit 1 is a verdict (uncalibrated, the profile's threshold sits inside this noise).
    assert result.exit_code in (0, 1), result.output
    assert json.loads(report.read_text())["model"]["predictors"] == {"speed": "linear-replay"}


def test_the_choice_can_be_narrowed(lagged: tuple[Path, Path, Path], tmp_path: Path):
    profile, _, folder = lagged
    logs = sorted(folder.glob("run_*.csv"))
    result = runner.invoke(app, ["train", *map(str, logs[:3]), "--holdout", str(logs[3]),
                                 "--profile", str(profile), "-o", str(tmp_path / "m"),
                                 "--iterations-scale", "0.02", "--hidden", "8",
                                 "--predictor", "network", "--keep-unskilled"])
    assert "skill per predictor" not in result.output      # one candidate: nothing to choose
    meta = json.loads((tmp_path / "m" / "model.json").read_text())
    assert meta["predictors"]["per_signal"] == {"speed": "network"}
    bad = runner.invoke(app, ["train", *map(str, logs), "--profile", str(profile), "-o",
                              str(tmp_path / "n"), "--predictor", "spline"])
    assert bad.exit_code == 2 and "unknown predictor spline" in bad.output


def _network_on_linear(seed: int) -> tuple[RecurrentDynamics, np.ndarray]:
    torch.manual_seed(seed)
    linear = np.random.default_rng(seed).normal(0, 0.05, (2 + 2 + 1, 2))
    linear[:2] -= 0.1 * np.eye(2)         # a stable linear model: its state decays
    linear = linear.astype(np.float32)
    return RecurrentDynamics(2, 2, 8, 0.1, linear), linear


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_the_network_on_a_linear_model_replays_as_torch_does(engine: str):
    pytest.importorskip("numba")
    network, linear = _network_on_linear(3)
    commands = np.random.default_rng(1).uniform(-1, 1, (1, 300, 2)).astype(np.float32)
    start = np.array([[0.3, -0.2]], np.float32)
    with torch.inference_mode():
        reference = network(torch.from_numpy(commands), torch.from_numpy(start)).numpy()
    fast = FastDynamics.from_state({k: v.numpy() for k, v in network.state_dict().items()},
                                   2, 0.1, linear)
    np.testing.assert_allclose(fast.rollout(commands, start, engine), reference, atol=2e-5)
    # The linear model alone is the linear part with nothing added.
    alone = linear_only(linear, 2).rollout(commands, start, engine)
    state = start[0].astype(np.float64)
    for k in range(1, 300):
        state = state + np.concatenate([state, commands[0, k - 1], [1.0]]) @ linear
        np.testing.assert_allclose(alone[0, k], state, rtol=1e-4, atol=1e-5)


def test_a_mixed_model_reads_each_signal_from_its_own_predictor_free_and_stepped():
    network, linear = _network_on_linear(5)
    on_linear = FastDynamics.from_state(
        {k: v.numpy() for k, v in network.state_dict().items()}, 2, 0.1, linear)
    alone = linear_only(linear, 2)
    mixed = ChosenDynamics((alone, on_linear), (1, 0))
    commands = np.random.default_rng(2).uniform(-1, 1, (1, 80, 2)).astype(np.float32)
    start = np.array([[0.1, 0.4]], np.float32)
    free = mixed.rollout(commands, start, "numpy")
    np.testing.assert_array_equal(free[..., 0], on_linear.rollout(commands, start,
                                                                  "numpy")[..., 0])
    np.testing.assert_array_equal(free[..., 1], alone.rollout(commands, start, "numpy")[..., 1])
    stepper = FastStepper(mixed, Normaliser((1.0, 1.0), (1.0, 1.0)))
    stepper.warm_up(commands[0, :40], start[0])
    np.testing.assert_allclose(stepper.current, free[0, 40], atol=1e-5)


def test_a_folder_of_a_days_logs_trains_leaving_out_those_never_operated(
        lagged: tuple[Path, Path, Path], tmp_path: Path):
    profile, _, folder = lagged
    day = tmp_path / "day"
    day.mkdir()
    for log in sorted(folder.glob("run_*.csv")):
        (day / log.name).write_bytes(log.read_bytes())
    write_linear_vehicle(day / "on_deck.csv", 20, seconds=60.0, idle=True)
    (day / "notes.txt").write_text("calm sea")
    result = runner.invoke(app, ["train", str(day), "--profile", str(profile), "-o",
                                 str(tmp_path / "m"), "--iterations-scale", "0.02",
                                 "--hidden", "8", "--predictor", "linear"])
    assert result.exit_code == 0, result.output
    assert "left out on_deck.csv: the vehicle never operates" in result.output
    assert "notes.txt: not a log this tool reads" in result.output
    meta = json.loads((tmp_path / "m" / "model.json").read_text())
    assert meta["trained_on"]["logs"] + len(meta["heldout_error"]["logs"]) == 4
    # Calibration leaves it out the same way; a folder of nothing but idle logs is refused.
    result = runner.invoke(app, ["calibrate", str(day), "--model", str(tmp_path / "m"),
                                 "--profile", str(profile)])
    assert result.exit_code == 0 and "left out on_deck.csv" in result.output, result.output
    idle = tmp_path / "idle"
    idle.mkdir()
    write_linear_vehicle(idle / "deck_1.csv", 21, seconds=60.0, idle=True)
    result = runner.invoke(app, ["train", str(idle), "--profile", str(profile), "-o",
                                 str(tmp_path / "n")])
    assert result.exit_code == 2
    assert "nothing to train on: the vehicle never operates in any of the 1 log(s)" in (
        result.output)
