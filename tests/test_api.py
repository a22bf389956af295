"""The public Python face: everything a program needs, from one module."""

import shutil
from pathlib import Path

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
    result = api.audit([fleet], tmp_path / "out")
    assert len(result.records) == 2 and result.count("fault") == 1
    assert (tmp_path / "out" / "audit.csv").is_file()


def test_everything_public_is_named_in_one_place():
    defined = {name for name, value in vars(api).items() if not name.startswith("_")
               and getattr(value, "__module__", None) == api.__name__}
    assert defined == {"audit", "diagnose", "load_model", "load_profile", "read_log", "to_json"}
    assert defined <= set(api.__all__) and all(hasattr(api, name) for name in api.__all__)
