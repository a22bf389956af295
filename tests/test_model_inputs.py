"""Measured inputs beside the commands (`[[inputs]]`): a glider-like vehicle whose depth
follows its pitch, which no command sets. Without the pitch the model cannot predict the
depth; with it declared as an input the depth is judged, the input is replayed as logged,
recorded in the model and the reports, and a model that needs it refuses a profile
without it."""

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app

pytestmark = pytest.mark.slow    # trains models or simulates fleets
# The linear model alone (the network is then not trained): how an input is read does not
# depend on the predictor (the network is trained with one in the test of a log that never
# fed it).
CHEAP_PREDICTORS = ("--predictor", "linear")

runner = CliRunner()
DT = 0.1


def write_pitched_vehicle(path: Path, seed: int, seconds: float = 240.0,
                          depth_stuck_from_s: float | None = None) -> Path:
    """Speed lags the thrust command; the depth changes at 0.5 m/s per radian of pitch (the
    pitch wanders on its own: trim, waves); ``depth_stuck_from_s``: the depth sensor holds
    its reading from then on."""
    rng = np.random.default_rng(seed)
    steps = round(seconds / DT)
    thrust = np.repeat(rng.uniform(0.2, 1.0, steps // 40 + 1), 40)[:steps]
    pitch = np.clip(np.cumsum(rng.normal(0, 0.01, steps)), -0.4, 0.4)
    speed, depth = np.zeros(steps), np.full(steps, 2.0)
    for k in range(1, steps):
        speed[k] = speed[k - 1] + DT * (thrust[k - 1] - speed[k - 1]) / 2.0
        depth[k] = depth[k - 1] + DT * 0.5 * np.sin(pitch[k - 1])
    measured = depth + rng.normal(0, 0.005, steps)
    if depth_stuck_from_s is not None:
        stuck = round(depth_stuck_from_s / DT)
        measured[stuck:] = measured[stuck]
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["t", "thrust", "pitch", "speed", "depth"])
        for k in range(steps):
            writer.writerow([f"{k * DT:.3f}", f"{thrust[k]:.4f}", f"{pitch[k]:.5f}",
                             f"{speed[k] + rng.normal(0, 0.005):.5f}", f"{measured[k]:.5f}"])
    return path


PROFILE = """
[vehicle]
name = "pitched"
description = "a vehicle whose depth follows its pitch"
dt_s = 0.1

[[commands]]
name = "thrust"
component = "thruster"

[[sensors]]
name = "speed"
component = "speed_sensor"
unit = "m/s"
full_scale = 1.0

[[sensors]]
name = "depth"
component = "depth_sensor"
unit = "m"
full_scale = 1.0
{inputs}
[matching]
window_samples = 20
decision_window_s = 3.0

[thresholds.mission]
speed = 15.0
depth = 15.0

[sources.csv]
time = { column = "t", unit = "s" }

[sources.csv.signals]
thrust = { column = "thrust" }
speed = { column = "speed" }
depth = { column = "depth" }
{pitch_source}
"""
PITCH_INPUT = """
[[inputs]]
name = "pitch"
unit = "rad"
description = "measured pitch angle"
"""


def _profile_text(inputs: str, pitch_source: str) -> str:
    return PROFILE.replace("{inputs}", inputs).replace("{pitch_source}", pitch_source)


def _profile(folder: Path, with_pitch: bool) -> Path:
    path = folder / ("with_pitch.toml" if with_pitch else "without_pitch.toml")
    path.write_text(_profile_text(PITCH_INPUT if with_pitch else "",
                                  'pitch = { column = "pitch" }' if with_pitch else ""))
    return path


def _train(folder: Path, logs: list[Path], profile: Path, name: str) -> tuple[Path, str]:
    output = folder / name
    result = runner.invoke(app, ["train", *map(str, logs[:3]), "--holdout", str(logs[3]),
                                 "--profile", str(profile), "-o", str(output),
                                 "--iterations-scale", "0.05", "--hidden", "8",
                                 "--keep-unskilled", *CHEAP_PREDICTORS])
    assert result.exit_code == 0, result.output
    return output, result.stdout


@pytest.fixture(scope="module")
def pitched(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("pitched")
    logs = [write_pitched_vehicle(folder / f"run_{seed}.csv", seed) for seed in range(4)]
    with_pitch, without_pitch = _profile(folder, True), _profile(folder, False)
    model, stdout = _train(folder, logs, with_pitch, "with_pitch")
    assert "driven by the commands and the measured inputs pitch" in stdout
    return {"folder": folder, "with": with_pitch, "without": without_pitch, "model": model,
            "blind_model": _train(folder, logs, without_pitch, "without_pitch")[0]}


def _skill(model: Path, signal: str) -> float:
    meta = json.loads((model / "model.json").read_text())
    return float(meta["skill"]["signals"][signal]["skill"])


def test_the_depth_is_judged_only_with_the_pitch_as_an_input(pitched: dict[str, Path]):
    assert _skill(pitched["blind_model"], "depth") < 1 / 3
    assert _skill(pitched["model"], "depth") > 0.6
    meta = json.loads((pitched["model"] / "model.json").read_text())
    (entry,) = meta["signals"]["inputs"]
    assert entry["name"] == "pitch" and entry["unit"] == "rad"
    assert -0.4 <= entry["typical"] <= 0.4
    assert meta["architecture"]["n_commands"] == 2       # the thrust and the pitch


def test_a_stuck_depth_sensor_is_found_and_the_report_names_the_input(
        pitched: dict[str, Path]):
    folder = pitched["folder"]
    reports = {}
    for name, stuck in (("normal", None), ("stuck", 60.0)):
        log = write_pitched_vehicle(folder / f"{name}.csv", 20, 150.0, stuck)
        result = runner.invoke(app, ["diagnose", str(log), "--profile", str(pitched["with"]),
                                     "--model", str(pitched["model"]), "--json",
                                     str(folder / f"{name}.json")])
        assert result.exit_code == (0 if stuck is None else 1), result.output
        assert "driven also by the measured pitch" in result.stdout
        reports[name] = json.loads((folder / f"{name}.json").read_text())
    assert reports["normal"]["verdict"] == "normal"
    assert reports["stuck"]["component"] == "depth_sensor"
    assert reports["stuck"]["onset_s"] == pytest.approx(60.0, abs=10.0)
    assert reports["stuck"]["model"]["inputs"] == ["pitch"]


def test_a_model_driven_by_an_input_refuses_a_profile_without_it(pitched: dict[str, Path]):
    log = write_pitched_vehicle(pitched["folder"] / "other.csv", 21, 60.0)
    result = runner.invoke(app, ["diagnose", str(log), "--profile", str(pitched["without"]),
                                 "--model", str(pitched["model"])])
    assert result.exit_code == 2
    assert "driven by the measured inputs ['pitch']" in result.output
    assert "train the model with this profile" in result.output
    assert str(log) in result.output


def test_a_model_given_alone_reads_logs_by_the_profile_it_was_trained_with(
        pitched: dict[str, Path]):
    folder = pitched["folder"]
    log = write_pitched_vehicle(folder / "alone.csv", 22, 60.0)
    given = runner.invoke(app, ["diagnose", str(log), "--model", str(pitched["model"]),
                                "--profile", str(pitched["with"])])
    alone = runner.invoke(app, ["diagnose", str(log), "--model", str(pitched["model"])])
    assert alone.exit_code == given.exit_code != 2, alone.output
    assert alone.stdout == given.stdout
    assert "driven also by the measured pitch" in alone.stdout
    # A copy of the model whose profile file is gone: the user is asked which it is.
    moved = folder / "moved_model"
    shutil.copytree(pitched["model"], moved)
    meta = json.loads((moved / "model.json").read_text())
    meta["profile"] = str(folder / "gone.toml")
    (moved / "model.json").write_text(json.dumps(meta))
    refused = runner.invoke(app, ["diagnose", str(log), "--model", str(moved)])
    assert refused.exit_code == 2
    (line,) = refused.output.strip().splitlines()
    assert str(moved) in line and "gone.toml" in line and "--profile" in line


def test_inspect_says_the_input_is_averaged_and_drives_the_model(pitched: dict[str, Path]):
    log = pitched["folder"] / "run_0.csv"
    result = runner.invoke(app, ["inspect", str(log), "--profile", str(pitched["with"])])
    assert result.exit_code == 0, result.output
    line = next(line for line in result.stdout.splitlines() if line.split()[:2] == ["ok", "pitch"])
    assert "a measured input of the model" in line


def test_an_input_named_like_a_sensor_is_refused(tmp_path: Path):
    text = _profile_text(PITCH_INPUT.replace('"pitch"', '"depth"', 1), "")
    (tmp_path / "p.toml").write_text(text)
    result = runner.invoke(app, ["inspect", str(tmp_path / "none.csv"), "--profile",
                                 str(tmp_path / "p.toml")])
    assert result.exit_code == 2
    assert "must be unique" in result.output


def _with_pitch(log: Path, out: Path, pitch: float) -> Path:
    """The log with its pitch column overwritten by one value throughout."""
    with log.open(newline="") as stream:
        rows = list(csv.reader(stream))
    column = rows[0].index("pitch")
    for row in rows[1:]:
        row[column] = f"{pitch:.6f}"
    with out.open("w", newline="") as stream:
        csv.writer(stream).writerows(rows)
    return out


def _without_pitch(log: Path, out: Path) -> Path:
    """The log without its pitch column."""
    with log.open(newline="") as stream:
        rows = list(csv.reader(stream))
    column = rows[0].index("pitch")
    with out.open("w", newline="") as stream:
        csv.writer(stream).writerows([row[:column] + row[column + 1:] for row in rows])
    return out


def test_an_input_a_log_never_fed_drives_the_model_at_its_typical_value(
        pitched: dict[str, Path]):
    """A pitch channel the logger filled with zeros would drive the model far from what it
    learnt; it is held at its typical value on the training logs, and the report says so.
    A log without the pitch column at all is read the same way, not refused."""
    from auvdiag_cli import api

    folder = pitched["folder"]
    log = write_pitched_vehicle(folder / "fed.csv", 22, 90.0)
    meta = json.loads((pitched["model"] / "model.json").read_text())
    typical = meta["signals"]["inputs"][0]["typical"]
    profile = api.load_profile(pitched["with"])
    model = api.load_model(pitched["model"], profile)
    zeros = api.diagnose(_with_pitch(log, folder / "zeros.csv", 0.0), profile, model)
    held = api.diagnose(_with_pitch(log, folder / "held.csv", typical), profile, model)
    assert any(note.startswith("pitch reads 0 throughout the log") and "typical value" in note
               for note in zeros.notes)
    assert typical != 0.0
    np.testing.assert_array_equal(zeros.histories.matching.modelled,
                                  held.histories.matching.modelled)
    absent = api.diagnose(_without_pitch(log, folder / "no_pitch.csv"), profile, model)
    assert any(note.startswith("pitch is not in this log") and "typical value" in note
               for note in absent.notes)
    np.testing.assert_array_equal(absent.histories.matching.modelled,
                                  held.histories.matching.modelled)


def test_training_holds_an_input_a_log_never_fed_and_says_so(pitched: dict[str, Path]):
    from auvdiag_cli import api

    folder = pitched["folder"]
    logs = [folder / f"run_{seed}.csv" for seed in range(4)]
    logs[1] = _with_pitch(logs[1], folder / "run_1_zero_pitch.csv", 0.0)
    logs[3] = _without_pitch(logs[3], folder / "run_3_no_pitch.csv")
    said: list[str] = []
    api.train(logs, api.load_profile(pitched["with"]), folder / "two_unfed",
              options=api.TrainOptions(iterations_scale=0.05, hidden=8, keep_unskilled=True,
                                       predictors=("network", "linear")),
              progress=said.append)
    (line,) = [line for line in said if line.startswith(
        "pitch: not fed (one value throughout, or not in the log) in 2 of 4 logs "
        "(run_1_zero_pitch.csv, run_3_no_pitch.csv): held at ")]
    held = float(line.split("held at ")[1].split(",")[0])
    # Its median over the logs that fed it, not pulled towards the zeros.
    fed = np.concatenate([np.loadtxt(logs[k], delimiter=",", skiprows=1, usecols=2)
                          for k in (0, 2)])
    assert held == pytest.approx(float(np.median(fed)), abs=0.01) and abs(held) > 0.05


def test_an_input_no_training_log_fed_is_held_where_it_was_not_read(pitched: dict[str, Path]):
    """Trained on logs whose pitch channel read 0 throughout (a sensor not fitted that day),
    the model never learnt how the pitch acts: a log that feeds it is replayed with it held
    at the value it had in training, as if the log had never fed it, and the report says so
    (fed as logged, it had driven an ALFA model of one day's flights into alarms on every
    flight of the other days)."""
    from auvdiag_cli import api

    folder = pitched["folder"]
    logs = [_with_pitch(folder / f"run_{seed}.csv", folder / f"run_{seed}_unfed.csv", 0.0)
            for seed in range(4)]
    said: list[str] = []
    profile = api.load_profile(pitched["with"])
    api.train(logs, profile, folder / "never_fed", options=api.TrainOptions(
        iterations_scale=0.05, hidden=8, keep_unskilled=True, predictors=("linear",)),
        progress=said.append)
    assert any(line.startswith("pitch: not fed") and "no log fed it: the model cannot learn"
               in line for line in said), said
    (entry,) = json.loads((folder / "never_fed" / "model.json").read_text())["signals"]["inputs"]
    assert entry["fed"] is False and entry["typical"] == 0.0
    assert json.loads((pitched["model"] / "model.json").read_text())["signals"]["inputs"][0][
        "fed"] is True
    model = api.load_model(folder / "never_fed", profile)
    log = write_pitched_vehicle(folder / "pitch_fed.csv", 23, 90.0)
    fed = api.diagnose(log, profile, model)
    unfed = api.diagnose(_with_pitch(log, folder / "pitch_zero.csv", 0.0), profile, model)
    np.testing.assert_array_equal(fed.histories.matching.modelled,
                                  unfed.histories.matching.modelled)
    assert any(note.startswith("pitch: no log the model was trained on fed it") and
               "held at 0" in note for note in fed.notes), fed.notes
    # A model that learnt it reads it from the log: the replay moves with it.
    learnt = api.load_model(pitched["model"], profile)
    assert not np.array_equal(api.diagnose(log, profile, learnt).histories.matching.modelled,
                              api.diagnose(folder / "pitch_zero.csv", profile,
                                           learnt).histories.matching.modelled)
