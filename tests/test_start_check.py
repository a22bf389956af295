"""A sensor that reads wrong from the first sample: the replay takes it as the truth, the
start check compares it with where normal logs recorded from rest start."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from auvdiag_cli.engine.ingest import ingest
from auvdiag_cli.engine.start_check import (
    FLOOR,
    MARGIN,
    check_start,
    learn_start_state,
    start_reading,
)
from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from models.card import StartReference
from models.store import default_model_dir

runner = CliRunner()


def test_a_start_is_read_only_from_rest():
    commands = np.zeros((30, 2))
    sensors = np.column_stack([np.full(30, 0.2), np.linspace(0.0, 0.29, 30)])
    sensors[0] = np.nan                           # the first complete step is the second
    reading = start_reading(commands, sensors, 0.1)
    assert reading is not None and np.allclose(reading.sensors, [0.2, 0.055])  # 1 s median
    commands[1] = [0.3, 0.0]                      # already driven: it may begin mid-dive
    assert start_reading(commands, sensors, 0.1) is None


def test_allowances_come_from_held_out_starts_with_a_floor():
    def at(*values: float):
        return start_reading(np.zeros((10, 1)), np.tile(values, (10, 1)), 0.1)

    training = [at(0.0, 0.00), at(0.01, 0.0), at(-0.01, 0.0)]
    refused = learn_start_state(training, [at(0.0, 0.0)], [1.0, 1.0])
    assert refused.refused and "needs normal logs recorded from rest" in refused.refused
    assert not refused.usable and refused.to_json() == {"refused": refused.refused}
    start = learn_start_state(training, [at(0.1, 0.0), at(0.0, 0.0), None, at(0.02, 0.01)],
                              [1.0, 1.0])
    assert start.reference == (0.0, 0.0) and start.heldout_logs == 3 and start.logs == 3
    assert start.thresholds == pytest.approx([MARGIN * 0.1, FLOOR])
    assert StartReference.from_json(start.to_json()) == start    # model.json round trip
    # Starts that scatter (a body rate in a swell) are not judged.
    scattered = [at(0.0, v) for v in (-0.3, -0.1, 0.0, 0.1, 0.3)]
    start = learn_start_state(scattered, scattered[:3], [1.0, 1.0])
    assert start.thresholds[0] is not None and start.thresholds[1] is None


def test_a_log_already_under_way_is_not_judged_and_said_so_in_the_vehicles_words():
    """A log whose commands already work on its first step (a flight cut from the air, a
    dive recorded from mid-water) says nothing at its start; the message calls the log
    what the vehicle's parts make it."""
    from auvdiag_cli.vehicle.actuators import outing

    assert outing(["set_point", "control_surface", "engine"]) == "flight"
    assert outing(["rotor"] * 4) == "flight"
    assert outing(["thruster", "thruster"]) == outing(["set_point"]) == "dive"
    assert outing(["rotor", "thruster"]) == "dive"

    def at(*values: float):
        return start_reading(np.zeros((10, 2)), np.tile(values, (10, 1)), 0.1)

    start = learn_start_state([at(0.0, 0.0)] * 3, [at(0.0, 0.0)] * 3, [1.0, 1.0])
    under_way = np.full((30, 2), 0.3)
    check = check_start(start, under_way, np.zeros((30, 2)), np.arange(30) * 0.1,
                        ["a", "b"], 0.1, "flight")
    assert not check.judged and check.why_not is not None
    assert check.why_not.endswith("it may begin mid-flight")
    # A model whose normal logs all began under way has no start either; the log's own
    # reason is the one given.
    refused = learn_start_state([], [], [1.0, 1.0])
    assert not refused.usable
    again = check_start(refused, under_way, np.zeros((30, 2)), np.arange(30) * 0.1,
                        ["a", "b"], 0.1, "flight")
    assert again.why_not == check.why_not


def _dive(profile, scenario: str, seed: int, target: Path) -> Path:
    write_log(simulate(get_scenario(scenario, profile), profile, seed), profile, target, "csv")
    return target


def test_a_flow_sensor_reading_high_from_the_first_sample_is_named(tmp_path, profile):
    readings = [start_reading(f.commands, f.sensors, profile.dt_s) for f in (
        ingest(_dive(profile, s, seed, tmp_path / f"{s}-{seed}.csv"), profile).frame
        for s in ("paper-normal", "mission-ccw") for seed in (41, 42, 43, 44))]
    start = learn_start_state(readings[:4], readings[4:], [0.5, 1.0])
    assert start.usable, start
    model = tmp_path / "model"
    model.mkdir()
    for file in default_model_dir().iterdir():
        (model / file.name).write_bytes(file.read_bytes())
    meta = json.loads((model / "model.json").read_text())
    (model / "model.json").write_text(json.dumps({**meta, "start_state": start.to_json()}))

    clean = _dive(profile, "paper-normal", 45, tmp_path / "clean.csv")
    table = pd.read_csv(clean)
    table["flow_mps"] += 0.04                     # 8 % of full scale, from the first sample
    biased = tmp_path / "biased.csv"
    table.to_csv(biased, index=False)
    report = {}
    for name, log in (("clean", clean), ("biased", biased)):
        report[name] = diagnose_json(log, "--model", str(model))[1]
    assert report["clean"]["verdict"] == "normal" and report["clean"]["start_check"]["judged"]
    biased_report = report["biased"]
    assert biased_report["verdict"] == "fault" and biased_report["component"] == "flow_sensor"
    assert biased_report["onset_s"] == 0.0 and biased_report["start_check"]["off"] == ["flow"]
    assert 0.03 < biased_report["start_check"]["deviation"]["flow"] < 0.05
    assert any(n.startswith("found at the start of the log: flow started +0.04") for n in
               biased_report["notes"])

    late = table[table["time_s"] >= table["time_s"].min() + 40.0]    # begins mid-dive
    late.to_csv(tmp_path / "late.csv", index=False)
    _, late_report = diagnose_json(tmp_path / "late.csv", "--model", str(model))
    assert not late_report["start_check"]["judged"]
    assert "not recorded from rest" in late_report["start_check"]["summary"]


def test_a_log_and_a_model_without_a_start_state_are_not_judged():
    check = check_start(StartReference(), np.zeros((5, 2)), np.zeros((5, 2)), np.arange(5) * 0.1,
                        ["flow", "yaw_rate"], 0.1)
    assert not check.judged and "train learns it" in check.describe({})
