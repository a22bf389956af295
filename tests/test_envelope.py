"""A model judges only where it learnt: a fault found after the vehicle went past what the
logs a model learnt from reached (its envelope) is not taken for a fault. On the simulated
BlueROV2 trained on three slow missions, a sprint at twice their speed is undetermined,
saying how far past the envelope it went, while a thruster lost mid-mission, which takes no
judged signal past it before its onset, is a fault named as before."""

from pathlib import Path

import numpy as np
import pytest

from auvdiag_cli.engine.envelope import MARGIN, beyond_before

pytestmark = pytest.mark.slow    # trains a model


def test_only_a_judged_signal_past_the_envelope_before_the_onset_counts():
    time_s = np.arange(0.0, 60.0, 0.1)
    sensors = np.zeros((len(time_s), 3))
    sensors[:, 0] = np.where(time_s > 40.0, 2.0, 0.5)        # past 1.25 x 1.0 from 40 s
    sensors[:, 1] = np.where(time_s > 5.0, 9.0, 0.1)         # far past, but not judged
    sensors[:, 2] = np.where(time_s > 45.0, -1.3, 0.2)       # past (|value|) from 45 s
    names = ("surge", "roll_rate", "yaw_rate")
    envelope = {"surge": 1.0, "roll_rate": 0.2, "yaw_rate": 1.0}
    judged = ["surge", "yaw_rate"]
    assert beyond_before(envelope, judged, names, time_s, sensors, onset_s=30.0) is None
    found = beyond_before(envelope, judged, names, time_s, sensors, onset_s=46.0)
    assert found is not None and found.signal == "surge"      # 2.0 / 1.0 beats 1.3 / 1.0
    assert found.since_s == pytest.approx(40.1) and found.reached == 2.0
    assert found.learnt * MARGIN < found.reached
    # Past it long before the onset (more than the look-back): the fault came later.
    assert beyond_before(envelope, judged, names, time_s, sensors[::-1], onset_s=59.0) is None
    assert beyond_before({}, judged, names, time_s, sensors, onset_s=46.0) is None


def test_a_signal_already_past_what_was_learnt_at_the_onset_counts_until_the_detection():
    """A sprint accelerating past the fastest mission learnt: its surge is past the envelope
    at the onset and past MARGIN times it before the detection. A signal within the
    envelope at the onset (a fault's effect begins there), or one that falls back within
    it before going further, does not count."""
    time_s = np.arange(0.0, 30.0, 0.1)
    names, judged, envelope = ("surge",), ["surge"], {"surge": 1.0}
    accelerating = (0.5 + 0.05 * time_s)[:, None]         # 1.0 at 10 s, 1.25 at 15 s
    found = beyond_before(envelope, judged, names, time_s, accelerating, onset_s=11.0,
                          detected_s=20.0)
    assert found is not None and found.since_s == pytest.approx(15.1, abs=0.05)
    assert found.reached == pytest.approx(1.5)
    assert beyond_before(envelope, judged, names, time_s, accelerating, onset_s=11.0,
                         detected_s=14.0) is None           # not past MARGIN x by then
    assert beyond_before(envelope, judged, names, time_s, accelerating, onset_s=11.0) is None
    assert beyond_before(envelope, judged, names, time_s, accelerating, onset_s=9.0,
                         detected_s=20.0) is None           # within it at the onset
    dipping = accelerating.copy()
    dipping[(time_s > 12.0) & (time_s < 13.0)] = 0.9
    assert beyond_before(envelope, judged, names, time_s, dipping, onset_s=11.0,
                         detected_s=20.0) is None


def test_a_sprint_past_three_slow_missions_is_undetermined_a_lost_thruster_a_fault(
        tmp_path: Path):
    from auvdiag_cli import api
    from auvdiag_cli.simulator.scenarios import get_scenario

    profile = api.load_profile("bluerov2")

    def flown(scenario: str, seed: int) -> Path:
        path = tmp_path / f"{scenario}-{seed}.tlog"
        api.simulate(get_scenario(scenario, profile), profile, path, log_format="tlog",
                     seed=seed)
        return path

    normal = [flown(name, 1) for name in ("paper-normal", "mission-ccw", "mission-large-cw")]
    trained = api.train(normal, profile, tmp_path / "model", options=api.TrainOptions(
        iterations_scale=0.05, hidden=8, predictors=("linear", "linear-replay")),
        progress=lambda _: None)
    model = api.load_model(tmp_path / "model", profile)
    learnt = dict(model.card.envelope)
    assert set(learnt) == set(profile.sensor_names) and 0.1 < learnt["surge"] < 0.25
    assert learnt == pytest.approx(dict(trained.envelope))
    from auvdiag_cli.reports.training import training_lines
    said = [line for line in training_lines(trained, {}, profile)
            if line.startswith("learnt up to (a fault found after a judged signal went past "
                               "1.25 times this is undetermined): ")]
    assert len(said) == 1 and f"surge {learnt['surge']:.3g} m/s" in said[0], said

    sprint = api.diagnose(flown("mission-sprint-ccw", 11), profile, model)
    assert sprint.verdict.value == "undetermined", sprint.notes
    assert sprint.undetermined_because == "the vehicle went past what the model learnt from"
    assert any(note.startswith("an alarm at ") and f"past the {learnt['surge']:.3g} it "
               "reached at most" in note for note in sprint.notes), sprint.notes
    report = api.build_report(sprint)
    assert report.to_json()["undetermined_because"] == sprint.undetermined_because
    assert api.summary_text(sprint).splitlines()[1] == (
        "verdict: UNDETERMINED: the vehicle went past what the model learnt from")

    lost = api.diagnose(flown("mission-thruster-2-dead", 21), profile, model)
    assert lost.verdict.value == "fault" and lost.component == "thruster_2", lost.notes
    assert lost.undetermined_because is None


def test_an_envelope_that_bounds_nothing_is_left_out_and_a_malformed_one_names_the_file(
        tmp_path: Path):
    """A model file edited by hand: a value that is no positive number bounds nothing (a
    negative one would make every fault undetermined); one that is no number at all is a
    one-line error naming the model."""
    import json

    from models.card import ModelCard
    from models.store import ModelFileError, load_model

    document = json.loads((Path(__file__).parents[1] / "models" / "bluerov2" / "model.json")
                          .read_text())
    document["envelope"] = {"sensors": {"surge": -1.0, "heave": float("nan"), "yaw_rate": 0.3}}
    assert dict(ModelCard.from_document(document).envelope) == {"yaw_rate": 0.3}
    model = tmp_path / "model"
    model.mkdir()
    for name in ("model.json", "weights.npz"):
        (model / name).write_bytes((Path(__file__).parents[1] / "models" / "bluerov2" / name)
                                   .read_bytes())
    document["envelope"] = {"sensors": {"surge": "fast"}}
    (model / "model.json").write_text(json.dumps(document))
    with pytest.raises(ModelFileError, match="could not convert"):
        load_model(model)
