"""The public Python face: everything a program needs, from one module."""

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from auvdiag_cli import api
from auvdiag_errors import AuvdiagError

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"


def test_a_program_reads_diagnoses_and_reports_a_log():
    profile = api.load_profile()
    model = api.load_model()
    log = SAMPLES / "paper-flow-sensor-covered"
    signals = api.read_log(log, profile)
    assert set(signals.series) >= {"thruster_0", "thruster_1", "flow", "yaw_rate"}
    diagnosis = api.diagnose(log, profile, model)
    assert diagnosis.verdict is api.Verdict.FAULT and diagnosis.component == "flow_sensor"
    report = api.to_json(diagnosis)
    assert report["verdict"] == "fault" and report["case"] == 2


def test_a_built_in_profile_by_name_and_errors_of_one_type():
    assert api.load_profile("bluerov2_standard").name == "bluerov2_standard"
    with pytest.raises(AuvdiagError, match="no-such-dive"):
        api.diagnose(Path("no-such-dive.bag"), api.load_profile(), api.load_model())


def test_the_shipped_model_is_the_profiles_vehicles_as_the_cli_picks_it():
    bluerov2 = api.load_profile("bluerov2")
    assert api.load_model(profile=bluerov2).card.vehicle == "bluerov2"
    assert api.load_model().card.vehicle == "twin-burger"
    with pytest.raises(AuvdiagError, match="no model is shipped for vehicle 'haizhe'"):
        api.load_model(profile=api.load_profile("haizhe"))


def test_a_program_audits_a_folder(tmp_path):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    for name in ("paper-normal", "mission-thruster-1-dead.mcap"):
        source = SAMPLES / name
        if source.is_dir():
            shutil.copytree(source, fleet / name)
        else:
            shutil.copy(source, fleet / name)
    result = api.audit([fleet], None, None, tmp_path / "out")
    assert len(result.records) == 2 and result.count("fault") == 1
    assert (tmp_path / "out" / "audit.csv").is_file()
    assert (tmp_path / "out" / "audit.pdf").read_bytes().startswith(b"%PDF")


def test_a_program_trains_calibrates_saves_diagnoses_reports_and_audits(make_log, tmp_path):
    """The CLI's path from normal logs to a fleet audit, on objects, with nothing printed."""
    profile = api.load_profile()
    logs = [make_log(name, 11) for name in ("dms-za", "dms-zb", "paper-normal",
                                             "mission-large-ccw")]
    options = api.TrainOptions((make_log("mission-ccw", 12),), iterations_scale=0.05,
                               predictors=("linear",), keep_unskilled=True)
    trained = api.train(logs, profile, tmp_path / "model", options=options)
    assert trained.written and dict(trained.chosen.predictors) == {"flow": "linear",
                                                                   "yaw_rate": "linear"}
    model = api.load_model(tmp_path / "model", profile)
    assert model.card.predictors == trained.chosen.predictors and not model.card.calibrated
    # The change test's predictor a moment ahead, fitted beside the network.
    assert model.card.ahead is not None and set(model.card.ahead.skill) == {"flow", "yaw_rate"}
    before = model.dynamics
    model.update_entries(predictors={"per_signal": {"flow": "linear", "yaw_rate": "linear"}})
    assert model.dynamics is not before            # the replay follows the entries
    calibration = api.calibrate([make_log("paper-normal", 13), make_log("mission-ccw", 14)],
                                profile, model)
    api.save_model(model, tmp_path / "calibrated")
    saved = api.load_model(tmp_path / "calibrated", profile)
    assert saved.card.calibrated and saved.card.thresholds is not None
    assert dict(saved.card.thresholds["mission"]) == calibration.thresholds["mission"]
    assert not api.load_model(tmp_path / "model", profile).card.calibrated   # untouched
    diagnosis = api.diagnose(make_log("paper-flow-sensor-covered", 11), profile, saved)
    judged = diagnosis.histories.change_residual
    assert judged is not None and saved.card.ahead is not None
    uncut = saved.card.ahead.residual(diagnosis.histories.commands,
                                      diagnosis.histories.matching.measured)
    known = np.isfinite(judged)        # the diagnosis also leaves out its re-starts
    assert known.mean() > 0.8 and np.array_equal(judged[known], uncut[known])
    api.write_reports(diagnosis, json=tmp_path / "d.json", pdf=tmp_path / "d.pdf",
                      mcap=tmp_path / "d.mcap")
    assert (tmp_path / "d.pdf").read_bytes().startswith(b"%PDF")
    assert json.loads((tmp_path / "d.json").read_text())["verdict"] == diagnosis.verdict
    assert (tmp_path / "d.mcap").stat().st_size > 0
    fleet = api.audit([make_log("paper-normal", 13), make_log("paper-flow-sensor-covered", 11)],
                      profile, saved, tmp_path / "audit")
    assert len(fleet.records) == 2 and all(r.model_path == str(tmp_path / "calibrated")
                                           for r in fleet.records)
    assert api.trend(tmp_path / "audit").short         # two dives: too few for a trend
    # An audit reads the model from its directory: one changed in memory is refused.
    api.calibrate([make_log("paper-normal", 13)], profile, saved)
    with pytest.raises(AuvdiagError, match="changes not saved to"):
        api.audit([make_log("paper-normal", 13)], profile, saved, tmp_path / "audit2")
    changed = dataclasses.replace(profile, dt_s=0.2)
    with pytest.raises(AuvdiagError, match="the profile differs from builtin:twin_burger"):
        api.audit([make_log("paper-normal", 13)], changed, model, tmp_path / "audit2")
    with pytest.raises(AuvdiagError, match="not an audit folder"):
        api.trend(tmp_path)


def test_everything_public_is_named_in_one_place():
    defined = {name for name, value in vars(api).items() if not name.startswith("_")
               and getattr(value, "__module__", None) == api.__name__}
    assert defined == {"audit", "build_report", "calibrate", "derive_table", "diagnose",
                       "draft_profile",
                       "inspect", "load_model", "load_profile", "log_format", "read_log",
                       "relate", "save_model", "scenarios", "score", "simulate", "summary_text",
                       "to_json",
                       "train", "trend", "write_reports"}
    assert defined <= set(api.__all__) and all(hasattr(api, name) for name in api.__all__)


def test_every_command_of_the_cli_has_its_function():
    from auvdiag_cli.cli import app

    renamed = {"init-profile": "draft_profile", "report": "redraw_report"}
    commands = {c.name or c.callback.__name__ for c in app.registered_commands}
    assert len(commands) >= 13
    for command in commands:
        assert callable(getattr(api, renamed.get(command, command.replace("-", "_")))), command


def test_a_program_simulates_its_own_scenario_and_redraws_a_saved_report(tmp_path):
    from dataclasses import replace

    profile = api.load_profile()
    scenario = replace(api.scenarios(profile)["paper-flow-sensor-covered"], name="mine")
    log = tmp_path / "mine.mcap"
    dive = api.simulate(scenario, profile, log, log_format="mcap", seed=3)
    assert dive.scenario.name == "mine" and api.log_format(log) == "mcap"
    with pytest.raises(AuvdiagError, match="exists already"):
        api.simulate(scenario, profile, log, log_format="mcap")
    with pytest.raises(AuvdiagError, match="no-such-scenario"):
        api.simulate("no-such-scenario", profile, tmp_path / "x.mcap")
    api.write_reports(api.diagnose(log, profile, api.load_model()), json=tmp_path / "d.json")
    assert api.redraw_report(tmp_path / "d.json", tmp_path / "d.pdf")
    assert (tmp_path / "d.pdf").read_bytes().startswith(b"%PDF")
    (tmp_path / "d.series.npz").unlink()
    assert not api.redraw_report(tmp_path / "d.json", tmp_path / "summary-only.pdf")
    with pytest.raises(AuvdiagError, match="not an auvdiag JSON report"):
        api.redraw_report(log.with_suffix(".truth.json"), tmp_path / "t.pdf")


def test_the_summary_text_is_what_diagnose_prints():
    from typer.testing import CliRunner

    from auvdiag_cli.cli import app

    log = SAMPLES / "paper-flow-sensor-covered"
    profile = api.load_profile()
    diagnosis = api.diagnose(log, profile, api.load_model(profile=profile))
    printed = CliRunner().invoke(app, ["diagnose", str(log)]).stdout
    assert printed == api.summary_text(diagnosis) + "\n"
    assert api.summary_text(diagnosis).startswith(f"{log}  (") and "verdict: FAULT" in printed
