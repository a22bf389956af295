"""A `values` map: the raw values a flag takes (integers, or texts such as a flight mode's
name or MOOS's helm state) and what each means, `"*"` what any other means; read the same
from every format that logs them."""

import csv
import re
from pathlib import Path

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from typer.testing import CliRunner

from adapters import read_log
from adapters.signals import OPERATING, FieldSource, LogSources, TimeColumn
from auvdiag_cli.cli import app
from auvdiag_cli.jobs.draft_text import entry
from auvdiag_cli.simulator.writers.records import operating_raw
from auvdiag_cli.simulator.writers.ros import RosMessages, _open_rosbag_writer
from auvdiag_cli.vehicle.profile import load_profile, profile_text
from auvdiag_errors import ProfileError

START_NS = 1_536_703_357_000_000_000
# An aircraft's flight modes, one a second: the pilot takes over for three seconds.
MODES = ["GUIDED"] * 4 + ["MANUAL"] * 3 + ["AUTO"] * 3
FLYING = [0.0 if mode == "MANUAL" else 1.0 for mode in MODES]
NOT_MANUAL = FieldSource("/mavros/state", "mode", values=(("MANUAL", 0.0),), otherwise=1.0)


def _state_bag(path: Path, fmt: str) -> Path:
    """mavros's vehicle state, as rosbags writes it into a ROS 1 bag or a ROS 2 bag."""
    messages = RosMessages(fmt == "bag", {"/mavros/state": "mavros_msgs/msg/State"})
    with _open_rosbag_writer(path, fmt) as writer:
        connection = writer.add_connection("/mavros/state", "mavros_msgs/msg/State",
                                           typestore=messages.store)
        for k, mode in enumerate(MODES):
            message = messages.zero("mavros_msgs/msg/State")
            message.connected, message.armed, message.mode = True, True, mode
            data = (messages.store.serialize_ros1 if fmt == "bag"
                    else messages.store.serialize_cdr)(message, "mavros_msgs/msg/State")
            writer.write(connection, START_NS + k * 10**9, data)
    return path


def _state_csv_folder(folder: Path) -> Path:
    """The same topic as `rostopic echo -p` exports it: one CSV of the folder."""
    folder.mkdir()
    with (folder / "flight-mavros-state.csv").open("w", newline="") as stream:
        rows = csv.writer(stream)
        rows.writerow(["%time", "field.header.seq", "field.header.stamp",
                       "field.header.frame_id", "field.connected", "field.armed",
                       "field.guided", "field.mode", "field.system_status"])
        for k, mode in enumerate(MODES):
            time_ns = START_NS + k * 10**9
            rows.writerow([time_ns, k, time_ns, "", "True", "True", "True", mode, 4])
    return folder


def _operating(path: Path, family: str, source: FieldSource) -> np.ndarray:
    series = read_log(path, {family: LogSources({OPERATING: source})}).series[OPERATING]
    assert np.array_equal(np.diff(series.times_ns), np.full(len(series) - 1, 10**9))
    return series.values


@pytest.mark.parametrize("fmt", ["bag", "db3", "mcap"])
def test_a_flight_mode_reads_as_the_operating_flag_from_a_ros_log(tmp_path, fmt):
    log = _state_bag(tmp_path / f"flight.{fmt}" if fmt == "bag" else tmp_path / "flight", fmt)
    assert _operating(log, "ros", NOT_MANUAL).tolist() == FLYING


def test_a_flight_mode_reads_the_same_from_the_per_topic_csv_export(tmp_path):
    folder = _state_csv_folder(tmp_path / "flight")
    assert _operating(folder, "ros", NOT_MANUAL).tolist() == FLYING
    # Only the modes listed count where no "*" says what the others mean.
    guided = FieldSource("/mavros/state", "mode", values=(("GUIDED", 1.0), ("MANUAL", 0.0)))
    assert _operating(folder, "ros", guided).tolist() == [1.0] * 4 + [0.0] * 3


def test_a_helm_state_reads_from_an_alog_and_a_csv_column(tmp_path):
    states = ["PARK"] * 3 + ["DRIVE"] * 5 + ["PARK"] * 2
    alog = tmp_path / "dive.alog"
    alog.write_text("%% LOGSTART    1750068000.0\n" + "".join(
        f"{k:.3f} IVPHELM_STATE pHelmIvP {state}\n" for k, state in enumerate(states)))
    driving = FieldSource("IVPHELM_STATE", "value", values=(("DRIVE", 1.0),), otherwise=0.0)
    expected = [1.0 if state == "DRIVE" else 0.0 for state in states]
    assert _operating(alog, "moos", driving).tolist() == expected
    table = tmp_path / "dive.csv"
    table.write_text("t,helm\n" + "".join(f"{k},{state}\n" for k, state in enumerate(states)))
    sources = LogSources({OPERATING: FieldSource("helm", "helm", values=driving.values,
                                                 otherwise=0.0)},
                         time=TimeColumn("t", "s"))
    assert read_log(table, {"csv": sources}).series[OPERATING].values.tolist() == expected


def test_a_csv_column_read_through_a_map_and_as_a_number_gives_each_its_values(tmp_path):
    """One mode column, the operating flag through a map and a signal of its own: each gets
    what it asks for (the number one was refused as "not numbers" before); a text column
    read as a number is still refused."""
    from auvdiag_errors import LogError

    table = tmp_path / "flight.csv"
    table.write_text("t,mode,helm\n" + "".join(
        f"{k},{mode},{'DRIVE' if mode else 'PARK'}\n" for k, mode in enumerate([0, 0, 4, 4, 10])))
    sources = LogSources({OPERATING: FieldSource("mode", "mode", values=((0, 0.0),),
                                                 otherwise=1.0),
                          "mode_number": FieldSource("mode", "mode")},
                         time=TimeColumn("t", "s"))
    series = read_log(table, {"csv": sources}).series
    assert series[OPERATING].values.tolist() == [0, 0, 1, 1, 1]
    assert series["mode_number"].values.tolist() == [0, 0, 4, 4, 10]
    both = LogSources({OPERATING: FieldSource("helm", "helm", values=(("DRIVE", 1.0),),
                                              otherwise=0.0),
                       "helm_number": FieldSource("helm", "helm")}, time=TimeColumn("t", "s"))
    with pytest.raises(LogError, match=r"helm.*not numbers"):
        read_log(table, {"csv": both})


def test_a_mode_number_and_every_other_read_from_a_telemetry_log(tmp_path):
    """ArduPlane's heartbeat says its mode by number (10 AUTO, 15 GUIDED, 0 MANUAL)."""
    vehicle = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    frames = [vehicle.heartbeat_encode(1, 3, 129, mode, 4).pack(vehicle)
              for mode in (15, 15, 0, 0, 10, 7)]
    log = tmp_path / "flight.tlog"
    log.write_bytes(b"".join((START_NS // 1000 + k * 10**6).to_bytes(8, "big") + bytes(frame)
                             for k, frame in enumerate(frames)))
    manual_is_off = FieldSource("HEARTBEAT", "custom_mode", values=((0, 0.0),), otherwise=1.0)
    assert _operating(log, "mavlink", manual_is_off).tolist() == [1, 1, 0, 0, 1, 1]
    assert operating_raw(manual_is_off) == 1.0          # what a simulated log writes
    assert operating_raw(NOT_MANUAL) not in ("MANUAL", "")


def test_a_profile_maps_texts_and_every_other_value_and_names_a_map_that_lists_none(tmp_path):
    text, _ = profile_text()
    start = text.index("[sources.moos]")
    end = text.index("\n[", text.index("[sources.moos.signals]") + 1)
    mapping = text[start:end].replace(
        "[sources.moos.signals]",
        'operating = { variable = "IVPHELM_STATE", values = { DRIVE = 1, "*" = 0 } }\n\n'
        "[sources.moos.signals]")
    path = tmp_path / "p.toml"
    path.write_text(text[:start] + mapping + text[end:], encoding="utf-8")
    source = load_profile(path).sources["moos"].signals[OPERATING]
    assert (source.values, source.otherwise) == ((("DRIVE", 1.0),), 0.0)
    assert entry(source, "moos") == ('{ variable = "IVPHELM_STATE", '
                                     'values = { DRIVE = 1, "*" = 0 } }')
    path.write_text(text[:start] + mapping.replace('{ DRIVE = 1, "*" = 0 }', "{}")
                    + text[end:], encoding="utf-8")
    with pytest.raises(ProfileError, match=re.escape(
            "key 'sources.moos.operating.values' lists no value")):
        load_profile(path)


def test_init_profile_drafts_the_helm_driving_as_the_operating_flag(tmp_path):
    lines = ["%% LOGSTART    1750068000.0"]
    for k in range(600):
        t = k / 10
        lines.append(f"{t:.3f} DESIRED_THRUST pMarinePID {40 + 20 * np.sin(t / 3):.2f}")
        lines.append(f"{t:.3f} NAV_SPEED uSimMarine {1.2 + 0.3 * np.sin(t / 3):.3f}")
        if k % 10 == 0:
            lines.append(f"{t:.3f} IVPHELM_STATE pHelmIvP {'PARK' if t < 5 else 'DRIVE'}")
            lines.append(f"{t:.3f} DEPLOY pMarineViewer {'false' if t < 5 else 'true'}")
    log = tmp_path / "dive.alog"
    log.write_text("\n".join(lines) + "\n")
    draft = tmp_path / "draft.toml"
    result = CliRunner().invoke(app, ["init-profile", str(log), "-o", str(draft)])
    assert result.exit_code == 0, result.output
    assert 'operating = { variable = "IVPHELM_STATE", values = { DRIVE = 1, "*" = 0 } }' \
        in draft.read_text()
    flag = read_log(log, load_profile(draft).sources).series[OPERATING]
    assert flag.values[flag.times_ns < 1750068005_000_000_000].max() == 0
    assert flag.values[flag.times_ns >= 1750068005_000_000_000].min() == 1
