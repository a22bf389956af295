"""MOOS-IvP alog files, written as pLogger writes them: read, inspected, drafted from."""

import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from adapters import detect_format, inventory, read_log
from auvdiag_cli.cli import app
from auvdiag_cli.vehicle.profile import Profile, load_profile, profile_text
from auvdiag_errors import LogError

LOGSTART_S = 1750068000.25
LOGSTART_NS = 1_750_068_000_250_000_000
STEPS = 600                     # 60 s at 10 Hz
MAPPING = """[sources.moos]
segment = { variable = "DMS_SEQUENCE" }
operating = { variable = "DEPLOY" }

[sources.moos.signals]
thruster_0 = { variable = "DESIRED_THRUST_L", scale = 0.01 }
thruster_1 = { variable = "DESIRED_THRUST_R", scale = 0.01 }
flow = { variable = "NODE_REPORT", field = "SPD", where = { NAME = "kayak" } }
yaw_rate = { variable = "IMU_YAW_RATE", where = { source = "iIMU" } }
"""


def _thrust(k: int) -> tuple[float, float]:
    swing = 20.0 * float(np.sin(k / 30.0))
    return 40.0 + swing, 40.0 - swing


def _write_alog(path: Path, header: bool = True) -> Path:
    """Ten hertz postings of a kayak's apps, pLogger's banner and padded columns; two apps
    post the yaw rate, one line is no posting."""
    lines = ["%" * 40, "%% LOG FILE:       ./LOG_KAYAK/LOG_KAYAK.alog",
             "%% FILE OPENED ON  Mon Jun 16 10:00:00 2025",
             f"%% LOGSTART               {LOGSTART_S}", "%" * 40] if header else []
    lines.append(f"{0.05:<14.3f} DEPLOY              pMarineViewer      false")
    lines.append(f"{0.06:<14.3f} DB_UPTIME           MOOSDB_kayak       0.06")
    lines.append(f"{0.08:<14.3f} DMS_SEQUENCE        pHelmIvP           MISSION")
    for k in range(STEPS):
        t = 0.1 + k * 0.1
        left, right = _thrust(k)
        lines += [f"{t:<14.3f} DESIRED_RUDDER      pMarinePID         {left - right!r}",
                  f"{t:<14.3f} DESIRED_SPEED       pHelmIvP           {1.0 + (k > 300)!r}",
                  f"{t:<14.3f} DESIRED_THRUST_L    pMarinePID         {left!r}",
                  f"{t:<14.3f} DESIRED_THRUST_R    pMarinePID         {right!r}",
                  f"{t + 0.01:<14.3f} NODE_REPORT         pNodeReporter      "
                  f"NAME=kayak,X={k * 0.05:.2f},Y=2.5,SPD={0.01 * k:.2f},HDG=90,TYPE=kayak",
                  f"{t + 0.015:<14.3f} NODE_REPORT         uFldNodeBroker     "
                  f"NAME=gilda,X=0,Y=0,SPD=9.99,HDG=0,TYPE=uuv",
                  f"{t + 0.02:<14.3f} IMU_YAW_RATE        iIMU               {0.001 * k!r}",
                  f"{t + 0.03:<14.3f} IMU_YAW_RATE        uSimMarine         {-1.0!r}"]
        if k == 10:
            lines += [f"{t:<14.3f} DEPLOY              pMarineViewer      true",
                      "this line is no posting"]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _profile(tmp_path: Path, mapping: str = MAPPING) -> Profile:
    text, _ = profile_text()
    start = text.index("[sources.moos]")
    end = text.index("\n[", text.index("[sources.moos.signals]") + 1)
    path = tmp_path / "kayak.toml"
    path.write_text(text[:start] + mapping + text[end:], encoding="utf-8")
    return load_profile(path)


def test_an_alog_reads_on_its_logstart_clock(tmp_path):
    log = _write_alog(tmp_path / "LOG_KAYAK.alog")
    assert detect_format(log) == "alog"
    signals = read_log(log, _profile(tmp_path).sources)
    assert signals.format == "alog"
    assert signals.start_ns == LOGSTART_NS + 50_000_000         # to the ns: LOGSTART exact
    thruster = signals.series["thruster_0"]
    assert len(thruster) == STEPS
    assert thruster.times_ns[0] == LOGSTART_NS + 100_000_000
    np.testing.assert_allclose(thruster.values, [_thrust(k)[0] / 100 for k in range(STEPS)])
    # a key of one vehicle's text postings, and one app's postings of a variable two post
    np.testing.assert_allclose(signals.series["flow"].values,
                               [round(0.01 * k, 2) for k in range(STEPS)])
    np.testing.assert_allclose(signals.series["yaw_rate"].values,
                               [0.001 * k for k in range(STEPS)])
    assert signals.series["operating"].values.tolist() == [0.0, 1.0]     # false, true
    assert [m.label for m in signals.markers] == ["MISSION"]
    assert any("1 line(s) that do not read" in note for note in signals.notes)
    assert signals.damage is None


def test_without_a_banner_an_alog_is_timed_from_its_start(tmp_path):
    log = _write_alog(tmp_path / "plain.alog", header=False)
    assert detect_format(log) == "alog"
    signals = read_log(log, _profile(tmp_path).sources)
    assert signals.start_ns == 50_000_000
    assert any("no %% LOGSTART header" in note for note in signals.notes)


def test_an_alog_cut_short_is_read_up_to_its_last_whole_line(tmp_path):
    whole = _write_alog(tmp_path / "whole.alog").read_bytes()
    cut = tmp_path / "cut.alog"
    cut.write_bytes(whole[:whole.rindex(b"IMU_YAW_RATE        iIMU") + 40])
    signals = read_log(cut, _profile(tmp_path).sources)
    assert signals.damage is not None and "cut short" in signals.damage.reason
    assert len(signals.series["yaw_rate"]) == STEPS - 1     # the cut posting left out
    assert len(signals.series["thruster_0"]) == STEPS


def test_an_unknown_app_or_variable_is_one_line_naming_it(tmp_path):
    log = _write_alog(tmp_path / "LOG_KAYAK.alog")
    wrong_app = _profile(tmp_path, MAPPING.replace('source = "iIMU"', 'source = "iDVL"'))
    with pytest.raises(LogError, match=r"IMU_YAW_RATE has no message with source = iDVL; "
                                       r"its values: .*iIMU"):
        read_log(log, wrong_app.sources)
    profile_path = tmp_path / "missing.toml"
    _profile(tmp_path, MAPPING.replace('"NODE_REPORT", field = "SPD", where = { NAME = "kayak" }',
                                       '"NAV_SPEED"'))
    profile_path.write_text((tmp_path / "kayak.toml").read_text(encoding="utf-8"))
    result = CliRunner().invoke(app, ["diagnose", str(log), "--profile", str(profile_path)])
    assert result.exit_code == 2
    assert re.search(r"LOG_KAYAK\.alog: .*flow \(NAV_SPEED\)", result.output)
    assert len(result.output.strip().splitlines()) == 1


def test_inspect_lists_each_variable_its_keys_and_who_posts_it(tmp_path):
    log = _write_alog(tmp_path / "LOG_KAYAK.alog")
    contents, family = inventory(log)
    assert family == "moos"
    topics = {t.name: t for t in contents.topics}
    assert topics["DESIRED_THRUST_L"].type == "double"
    assert topics["DESIRED_THRUST_L"].count == STEPS
    report = topics["NODE_REPORT"]
    assert report.type == "string"
    assert report.fields == ("value", "source", "NAME", "X", "Y", "SPD", "HDG", "TYPE")
    assert topics["IMU_YAW_RATE"].instances == (("source", ("iIMU", "uSimMarine")),)
    assert topics["DEPLOY"].count == 2
    assert contents.notes == ["1 line(s) that do not read as TIME VARIABLE SOURCE VALUE left "
                              "out"]                       # the banner's lines are no damage
    result = CliRunner().invoke(app, ["inspect", str(log)])
    assert result.exit_code == 0 and "alog (profile mapping: [sources.moos])" in result.output


def test_init_profile_drafts_a_moos_mapping_that_reads_the_log(tmp_path, make_log):
    log = make_log("paper-normal", 11, "alog")
    draft = tmp_path / "draft.toml"
    result = CliRunner().invoke(app, ["init-profile", str(log), "--output", str(draft)])
    assert result.exit_code == 0, result.output
    text = draft.read_text(encoding="utf-8")
    assert 'desired_thrust_l = { variable = "DESIRED_THRUST_L", scale = 0.01 }' in text
    assert 'imu_yaw_rate = { variable = "IMU_YAW_RATE" }' in text
    profile = load_profile(draft)
    assert profile.command_names == ("desired_thrust_l", "desired_thrust_r")
    assert set(profile.sensor_names) == {"flow_velocity", "imu_yaw_rate"}
    signals = read_log(log, profile.sources)
    assert set(signals.series) == {*profile.command_names, *profile.sensor_names}


def test_an_audit_walks_plogger_folders_and_judges_each_alog(tmp_path, make_log):
    """pLogger writes each run into a folder of its own, beside the mission files it
    copies (`._moos`, `._bhv`): each alog is a log, a damaged one a row with its error."""
    import csv
    import shutil

    fleet = tmp_path / "fleet"
    for name, scenario in (("LOG_A_01_12_2026", "paper-normal"),
                           ("LOG_B_01_12_2026", "paper-flow-sensor-covered")):
        folder = fleet / name
        folder.mkdir(parents=True)
        shutil.copy(make_log(scenario, 11, "alog"), folder / f"{name}.alog")
        (folder / f"{name}._moos").write_text("ServerPort = 9000\n", encoding="utf-8")
    (fleet / "LOG_C_01_12_2026").mkdir()
    (fleet / "LOG_C_01_12_2026" / "LOG_C.alog").write_bytes(b"\x00\x01 not text")
    result = CliRunner().invoke(app, ["audit", str(fleet), "--output", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output          # the damaged one is not analysable
    with (tmp_path / "out" / "audit.csv").open() as stream:
        rows = {Path(row["log"]).name: row for row in csv.DictReader(stream)}
    assert set(rows) == {"LOG_A_01_12_2026.alog", "LOG_B_01_12_2026.alog", "LOG_C.alog"}
    assert rows["LOG_A_01_12_2026.alog"]["verdict"] == "normal"
    assert rows["LOG_B_01_12_2026.alog"]["verdict"] == "fault"
    assert rows["LOG_B_01_12_2026.alog"]["component"] == "flow_sensor"
    assert "not a log this tool reads" in rows["LOG_C.alog"]["error"]


def test_an_alog_names_its_vehicle_by_its_moos_community(tmp_path):
    from adapters.identity import log_identity

    log = _write_alog(tmp_path / "LOG_KAYAK.alog")
    said = log_identity(log, "alog")
    assert said is not None and said.vehicle == "moos-kayak" and said.distinctive
    default = tmp_path / "default.alog"
    default.write_bytes(log.read_bytes().replace(b"MOOSDB_kayak", b"MOOSDB_#1"))
    unnamed = log_identity(default, "alog")
    assert unnamed is not None and not unnamed.distinctive          # MOOS's default
    anonymous = tmp_path / "anonymous.alog"
    anonymous.write_bytes(log.read_bytes().replace(b"DB_UPTIME", b"UPTIME"))
    assert log_identity(anonymous, "alog") is None


def test_init_profile_takes_the_pid_outputs_as_commands_and_no_set_point_as_a_sensor(tmp_path):
    log = _write_alog(tmp_path / "LOG_KAYAK.alog")
    draft = tmp_path / "draft.toml"
    result = CliRunner().invoke(app, ["init-profile", str(log), "--output", str(draft)])
    assert result.exit_code == 0, result.output
    profile = load_profile(draft)
    assert set(profile.command_names) == {"desired_rudder", "desired_thrust_l",
                                          "desired_thrust_r"}
    assert "desired_speed" not in profile.sensor_names
    assert "imu_yaw_rate" in profile.sensor_names
    sources = profile.sources["moos"]
    assert sources.signals["imu_yaw_rate"].where == (("source", "iIMU"),)
    assert sources.signals["operating"].topic == "DEPLOY"
    assert sources.signals["desired_thrust_l"].scale == 0.01          # percent
    assert sources.signals["desired_rudder"].scale == pytest.approx(1 / 40)  # degrees


def test_a_source_logged_with_its_aux_is_filtered_on_the_app(tmp_path):
    """pLogger's LogAuxSrc writes the source as APP:AUX (``pHelmIvP:loiter``): `source` is
    the app, as without it, and `source_aux` the rest."""
    plain = _write_alog(tmp_path / "plain.alog")
    aux = tmp_path / "aux.alog"
    aux.write_text(plain.read_text(encoding="utf-8").replace(" iIMU ", " iIMU:gyro_0 ")
                   .replace(" uSimMarine ", " uSimMarine:sim "), encoding="utf-8")
    profile = _profile(tmp_path)
    read, expected = read_log(aux, profile.sources), read_log(plain, profile.sources)
    assert np.array_equal(read.series["yaw_rate"].values, expected.series["yaw_rate"].values)
    by_aux = _profile(tmp_path, MAPPING.replace('where = { source = "iIMU" }',
                                                'where = { source_aux = "gyro_0" }'))
    assert np.array_equal(read_log(aux, by_aux.sources).series["yaw_rate"].values,
                          expected.series["yaw_rate"].values)
    topics = {t.name: t for t in inventory(aux)[0].topics}
    assert topics["IMU_YAW_RATE"].instances == (("source", ("iIMU", "uSimMarine")),)
    assert topics["IMU_YAW_RATE"].fields == ("value", "source", "source_aux")
    assert topics["DESIRED_THRUST_L"].fields == ("value", "source")
