"""Profiles validate once, and a bad one names the offending key."""

import re
from pathlib import Path

import numpy as np
import pytest

from auvdiag_cli.vehicle.profile import load_profile
from auvdiag_errors import ProfileError


def test_builtin_profile_has_the_papers_figures(profile):
    assert profile.command_names == ("thruster_0", "thruster_1")
    assert profile.sensor_names == ("flow", "yaw_rate")
    assert profile.thresholds["mission"] == {"flow": 15.0, "yaw_rate": 10.0}
    for dms in ("ZA", "ZB", "ZC"):
        assert profile.thresholds[dms] == {"flow": 8.0, "yaw_rate": 7.0}
    table = {row.case: (row.b["flow"], row.b["yaw_rate"], row.components)
             for row in profile.pattern}
    assert table == {0: (0, 0, ()), 1: (1, 1, ("thruster_0", "thruster_1")),
                     2: (1, 0, ("flow_sensor",)), 3: (0, 1, ("yaw_rate_sensor",))}


BUILTIN = load_profile().source_path


@pytest.mark.parametrize(("edit", "message"), [
    (("full_scale = 0.5", 'full_scale = "big"'), "sensors[0].full_scale' must be a number"),
    (("full_scale = 0.5", "full_scale = -1.0"), "sensors[0].full_scale' must be positive"),
    (("[thresholds.mission]\nflow = 15.0\n", "[thresholds.mission]\n"),
     "missing key 'thresholds.mission.flow'"),
    (("dt_s = 0.1 ", "dt_x = 0.1 "), "missing key 'vehicle.dt_s'"),
    (("b = { flow = 1, yaw_rate = 0 }", "b = { flow = 2, yaw_rate = 0 }"),
     "pattern[2].b.flow' must be 0 or 1"),
    (('field = "data[0]"', "fieldx = 1"), "sources.ros.signals.thruster_0.field"),
    (('field = "data[0]"', 'field = "data[x]"'),
     "key 'sources.ros.signals.thruster_0.field': cannot parse field path 'data[x]'"),
    (('field = "twist.linear.x"', 'field = "twist..x"'),
     "key 'sources.ros.signals.flow.field': empty step in field path 'twist..x'"),
    (('field = "servo1_raw"', 'field = "servo1_raw", where = { "in stance" = 1 }'),
     "key 'sources.mavlink.signals.thruster_0.where.in stance': cannot parse field path"),
    (("[5, 0.6, 0.3]", "[5, 0.6]"), "dms.ZA.steps[0]"),
    (("[vehicle]", "[vehicle"), "not valid TOML"),
    (('components = ["flow_sensor"]', 'components = ["flow_sensr"]'),
     "key 'pattern[2].components' names unknown component 'flow_sensr'"),
    (("case = 3", "case = 1"), "key 'pattern[3].case' repeats case 1 of pattern[1]"),
    (("b = { flow = 0, yaw_rate = 1 }", "b = { flow = 1, yaw_rate = 0 }"),
     "key 'pattern[3].b' repeats the b vector of pattern[2] (case 2)"),
    (("b = { flow = 0, yaw_rate = 1 }", "b = { flow = 0 }"),
     "missing key 'pattern[3].b.yaw_rate'"),
    (("b = { flow = 0, yaw_rate = 1 }", "b = { flow = 0, yaw_rate = 1, depth = 0 }"),
     "key 'pattern[3].b.depth' names no sensor"),
])
def test_invalid_profile_names_the_key(tmp_path, edit, message):
    from importlib import resources

    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    assert edit[0] in text
    path = tmp_path / "p.toml"
    path.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(ProfileError, match=re.escape(message)):
        load_profile(path)


def test_missing_profile_file(tmp_path):
    with pytest.raises(ProfileError, match="cannot read profile"):
        load_profile(tmp_path / "absent.toml")


def test_the_pattern_table_is_optional(make_log, profile_without):
    from auvdiag_cli.engine.diagnosis import diagnose
    from models.store import load_model

    profile = load_profile(profile_without("[[pattern]]", "[dms."))
    assert profile.pattern == ()
    result = diagnose(make_log("paper-flow-sensor-covered", 11), profile, load_model())
    assert result.verdict == "fault" and result.b == {"flow": 1, "yaw_rate": 0}
    assert result.case is None and result.component == "flow_sensor"    # by the hypotheses
    assert not any("pattern table" in note for note in result.notes)   # not on every log


@pytest.mark.parametrize(("replacement", "message"), [
    ('values = {}', "key 'sources.dataflash.operating[1].values' lists no value"),
    ('values = { 10 = "yes", 11 = 0 }', "key 'sources.dataflash.operating[1].values.10' must "
                                        "be a number"),
])
def test_a_value_map_that_lists_nothing_or_no_number_names_its_key(tmp_path, replacement,
                                                                   message):
    from importlib import resources

    text = (resources.files("auvdiag_cli.vehicle") / "profiles/bluerov2_standard.toml"
            ).read_text()
    assert "values = { 10 = 1, 11 = 0 }" in text
    path = tmp_path / "p.toml"
    path.write_text(text.replace("values = { 10 = 1, 11 = 0 }", replacement))
    with pytest.raises(ProfileError, match=re.escape(message)):
        load_profile(path)


def test_the_operating_fallback_is_read_as_a_value_map():
    sources = load_profile(Path("bluerov2_standard")).sources["dataflash"]
    fallback = sources.fallbacks["operating"]
    assert (fallback.topic, fallback.field, fallback.values) == ("EV", "Id", ((10, 1.0),
                                                                               (11, 0.0)))
    converted = fallback.convert(np.array([10, 7, 11]))
    assert converted[0] == 1 and np.isnan(converted[1]) and converted[2] == 0


@pytest.mark.parametrize(("profile_name", "old", "new", "message"), [
    ("crazyflie", 'name = "motor_2"\ncomponent = "motor_2"\nkind = "rotor"',
     'name = "motor_2"\ncomponent = "motor_2"\nkind = "thruster"',
     "key 'effort[0].actuators' mixes kinds rotor, thruster"),
    ("crazyflie", 'kind = "rotor"', 'kind = "propeller"',
     "key 'commands[0].kind' must be one of thruster, rotor, control_surface, engine, "
     "set_point"),
    ("arduplane_carbonz", 'moved_by = ["rudder"]', 'moved_by = ["tail"]',
     "key 'sensors[4].moved_by' names 'tail', which is no actuator or command component"),
    ("arduplane_carbonz", 'kind = "engine"', 'kind = "jet"',
     "key 'actuators[3].kind' must be one of"),
    ("arduplane_carbonz", 'own_log_only = "the ground speed', 'own_log_only = 3 # "',
     "key 'sensors[6].own_log_only' must be a string, got 3"),
    ("bluerov2", 'sway = "sway"\nroll_rate', 'sway = "drift"\nroll_rate',
     "key 'controller.sway' names no sensor"),
    # A key no part of the profile reads (a typo) would be dropped without a word: the
    # setting it meant to make silently not made.
    ("arduplane_carbonz", 'own_log_only = "the ground speed', 'own_log_onyl = "the ground speed',
     "unknown key 'sensors[6].own_log_onyl' (a typo? 'sensors[6]' takes: below_only, "
     "component, description, full_scale, moved_by, name, own_log_only, signature_only, "
     "truth_column, unit)"),
    # A signal judged only within a signature has no way of its own to judge.
    ("arduplane_carbonz", 'signature_only = "rising', 'below_only = "x"\nsignature_only = "rising',
     "key 'sensors[5].below_only': 'climb' is judged only within a part's signature "
     "(signature_only), which is judged one way already"),
    ("arduplane_carbonz", "[[tracking]]", "[[trackin]]",
     "unknown key 'trackin' (a typo? the profile's tables:"),
    ("arduplane_carbonz", 'pitch_sp = { topic = "/mavros/nav_info/pitch"',
     'pitch_sp = { topic = "/mavros/nav_info/pitch", fild = "x"',
     "unknown key 'sources.ros.signals.pitch_sp.fild'"),
    ("bluerov2", "[sources.mavlink.signals]",
     "[sources.mavlink.signals]\nheadng = { message = 'VFR_HUD', field = 'groundspeed' }",
     "unknown key 'sources.mavlink.signals.headng' (a typo? 'sources.mavlink.signals' "
     "takes:"),
])
def test_actuator_kinds_what_moves_a_sensor_and_unknown_keys_are_checked(
        tmp_path, profile_name, old, new, message):
    from auvdiag_cli.vehicle.profile import profile_text

    text, _ = profile_text(Path(profile_name))
    assert old in text
    path = tmp_path / "p.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ProfileError, match=re.escape(message)):
        load_profile(path)
