"""A part's signature in the change test: several signals moved a little the same way by
one weakened part, judged together and one-sided, name that part."""

import re
from pathlib import Path

import numpy as np
import pytest

from auvdiag_cli import api
from auvdiag_cli.engine.change_check import check_change
from auvdiag_cli.engine.change_signatures import (
    signature_names,
    signature_only,
    signatures,
    thresholded,
)
from auvdiag_cli.engine.change_statistics import SUM, WINDOW
from auvdiag_cli.engine.change_suspects import change_suspects
from auvdiag_cli.vehicle.profile import load_profile, profile_text
from auvdiag_errors import ProfileError

DT_S, STEPS = 0.1, 10
ENGINE = ["pitch", "climb", "ground_speed", "accel_x"]


def _log(shift: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """150 s of residual noise on the four signals an engine moves; from 90 s each reads
    ``shift`` spreads of a window mean from its prediction (a window mean of ten unit
    samples has a spread of about 0.32)."""
    residual = np.random.default_rng(seed).normal(0.0, 1.0, (1500, len(ENGINE)))
    residual[900:] += shift * 0.32
    return residual, np.arange(1500) * DT_S


def _thresholds(names: list[str]) -> dict[str, dict[str, float]]:
    return {WINDOW: dict.fromkeys(names, 6.0), SUM: dict.fromkeys(names, 8.0)}


def test_four_signals_a_spread_below_name_the_engine_none_of_them_alone_crosses():
    """Each signal a spread below its prediction: a CUSUM that allows a spread gains
    nothing on any one, while their signed sum gains a spread a window."""
    profile = api.load_profile("arduplane_carbonz")
    names = [*ENGINE, *signature_names(profile.actuators, ENGINE)]
    assert names[-1] == "engine weakened"
    found, alone = 0, 0
    for seed in range(5):
        residual, time_s = _log(-1.0, seed)
        check = check_change(residual, ENGINE, _thresholds(names), time_s, STEPS, DT_S,
                             profile.actuators)
        without = check_change(residual, ENGINE, _thresholds(ENGINE), time_s, STEPS, DT_S,
                               profile.actuators)
        alone += without.alarm_s is not None
        if check.alarm_s is not None and 90.0 <= check.alarm_s <= 105.0:
            found += 1
            assert "engine weakened" in check.flagged
            assert change_suspects(check.flagged, profile, check.evidence)[0] == "engine"
    assert found >= 4 and alone <= 1


def test_a_move_against_the_signature_is_no_evidence_for_it():
    """The same shift the other way (a surface stuck nose up) leaves the signature's sum
    near nothing, where the shift it describes drives it past its threshold."""
    profile = api.load_profile("arduplane_carbonz")
    names = [*ENGINE, "engine weakened"]
    for seed in range(3):
        peaks = {}
        for shift in (-1.0, 1.0):
            residual, time_s = _log(shift, seed)
            check = check_change(residual, ENGINE, _thresholds(names), time_s, STEPS, DT_S,
                                 profile.actuators)
            peaks[shift] = check.peaks[SUM]["engine weakened"]
        assert peaks[1.0] < 3.0 < 8.0 < peaks[-1.0]


def test_a_signature_needs_two_judged_members():
    profile = api.load_profile("arduplane_carbonz")
    assert signature_names(profile.actuators, ["climb", "roll"]) == []
    (engine,) = signatures(profile.actuators, ["roll", "climb", "accel_x"])
    assert engine.part == "engine" and dict(engine.signs) == {1: -1.0, 2: -1.0}


@pytest.mark.parametrize(("old", "new", "message"), [
    ("pitch = -1, climb", "pitch = 2, climb",
     "key 'actuators[3].weakened.pitch' must be 1 or -1"),
    ("pitch = -1, climb", "altitude = -1, climb",
     "actuator 'engine': 'weakened' names 'altitude', which is no sensor"),
    ('moved_by = ["rudder"]\nown_log_only', 'moved_by = ["rudder"]\nsignature_only = "x"\n'
     "own_log_only", "key 'sensors[4].signature_only': 'yaw_rate' is in no actuator's "
     "'weakened', so nothing would judge it"),
])
def test_a_signature_names_sensors_with_a_sign(tmp_path, old, new, message):
    text, _ = profile_text(Path("arduplane_carbonz"))
    assert old in text
    path = tmp_path / "p.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ProfileError, match=re.escape(message)):
        load_profile(path)


def test_a_signal_judged_only_within_a_signature_never_alarms_alone():
    """The climb, moved by rising and sinking air with no failure, is judged only within the
    engine's signature: a shift of it alone raises nothing, while the four moving together
    still name the engine."""
    profile = api.load_profile("arduplane_carbonz")
    alone = signature_only(profile.sensors)
    assert alone == {"climb"}
    names = thresholded(profile.actuators, profile.sensors, ENGINE)
    assert "climb" not in names and "engine weakened" in names
    rng = np.random.default_rng(4)
    residual = rng.normal(0.0, 1.0, (1500, len(ENGINE)))
    residual[900:, ENGINE.index("climb")] += 3.0          # the climb alone, far off
    time_s = np.arange(1500) * DT_S
    judged_alone = check_change(residual, ENGINE, _thresholds([*ENGINE, "engine weakened"]),
                                time_s, STEPS, DT_S, profile.actuators)
    assert judged_alone.alarm_s is not None and "climb" in judged_alone.flagged
    quiet = check_change(residual, ENGINE, _thresholds(names), time_s, STEPS, DT_S,
                         profile.actuators, within_signatures=alone)
    assert quiet.alarm_s is None and "climb" in quiet.members["engine weakened"]
    residual, time_s = _log(-1.0, 0)
    engine = check_change(residual, ENGINE, _thresholds(names), time_s, STEPS, DT_S,
                          profile.actuators, within_signatures=alone)
    assert engine.alarm_s is not None and "engine weakened" in engine.flagged
