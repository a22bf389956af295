"""A ROS log exported as per-topic CSVs (`rostopic echo -p`): a folder of them is one log,
read with the profile's [sources.ros] mapping, with the same result as the bag it came from;
damaged, cut or shuffled topic files and a missing topic are handled like any log's; an
audit root of such folders audits each as one log. The real ALFA flights read the same from
their bag and from their CSV folder."""

import csv
import json
import random
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_json
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from adapters import detect_format, inventory, read_log
from adapters.signals import CLOCK_REFERENCE, FieldSource, LogSources
from auvdiag_cli import api
from auvdiag_cli.audit.discovery import discover
from auvdiag_cli.cli import app
from auvdiag_cli.simulator.writers import write_log
from auvdiag_errors import LogError

runner = CliRunner()
SCENARIO, SEED = "paper-flow-sensor-covered", 31
ALFA = SHARED_DATA / "alfa"
# The flights kept in both forms (a bag beside its CSVs); one placeholder where there is no
# data, for the shared_data mark to skip.
ALFA_WITH_BAGS = sorted(bag.parent.name for bag in ALFA.glob("*/*.bag")) or ["absent"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory, dive_cache, profile):
    """One simulated dive as a ROS 1 bag and as that bag's per-topic CSV export."""
    folder = tmp_path_factory.mktemp("export")
    dive = dive_cache(SCENARIO, SEED)
    write_log(dive, profile, folder / "dive.bag", "bag")
    write_log(dive, profile, folder / "flight", "topic-csv")
    return folder / "dive.bag", folder / "flight"


def _diagnosis(log: Path):
    return api.diagnose(log, api.load_profile(None), api.load_model(None))


def _summary(diagnosis) -> tuple:
    return (diagnosis.verdict, diagnosis.component, diagnosis.onset_s, diagnosis.detected_at_s,
            dict(diagnosis.segments[0].max_g))


def test_a_bag_and_its_topic_csv_export_give_the_same_diagnosis(exported):
    bag, folder = exported
    assert detect_format(folder) == "topic-csv"
    header = (folder / "flight-thrusters-command.csv").read_text().splitlines()[0]
    assert header.startswith("%time,") and "field.data0" in header
    from_bag, from_csv = _diagnosis(bag), _diagnosis(folder)
    assert from_csv.verdict == "fault" and from_csv.component == "flow_sensor"
    assert _summary(from_csv) == _summary(from_bag)


def test_one_topic_csv_alone_is_a_log_of_its_topic(exported):
    _, folder = exported
    single = folder / "flight-imu-data.csv"
    held, family = inventory(single)
    assert family == "ros" and held.format == "topic-csv"
    assert [t.name for t in held.topics] == ["/imu/data"]
    assert "angular_velocity.z" in held.topics[0].fields and held.duration_s > 100


def test_a_renamed_folder_still_reads_its_topics(exported, tmp_path):
    """Files named after a dated recording (`rostopic echo -p` exports of
    `flight_2026-11-22-10-00-00.bag`) in a folder renamed since: the recording's name is
    what every file begins with up to its last part that starts with a digit, which no ROS
    name's part does; the topics read as from the folder with the recording's name."""
    bag, folder = exported
    renamed = tmp_path / "dive 42"
    renamed.mkdir()
    for file in folder.glob("*.csv"):
        topic = file.name.removeprefix("flight-")
        shutil.copy(file, renamed / f"flight_2026-11-22-10-00-00-{topic}")
    held, _ = inventory(renamed)
    assert {t.name for t in held.topics} == {t.name for t in inventory(folder)[0].topics}
    diagnosis = _diagnosis(renamed)
    assert not any("namespace" in note for note in diagnosis.notes), diagnosis.notes
    assert _summary(diagnosis) == _summary(_diagnosis(bag))


def test_a_missing_topic_is_one_line_naming_the_folder_and_topic(exported, tmp_path):
    _, folder = exported
    damaged = tmp_path / "flight"
    shutil.copytree(folder, damaged)
    (damaged / "flight-flow-velocity.csv").unlink()
    result = runner.invoke(app, ["diagnose", str(damaged), "--quiet"])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and str(damaged) in lines[0] and "/flow/velocity" in lines[0]


def test_cut_and_shuffled_topic_files_still_read(exported, tmp_path):
    bag, folder = exported
    damaged = tmp_path / "flight"
    shutil.copytree(folder, damaged)
    imu = damaged / "flight-imu-data.csv"
    text = imu.read_bytes()
    imu.write_bytes(text[:len(text) - 40])                # the last row cut in half
    commands = damaged / "flight-thrusters-command.csv"
    header, *rows = commands.read_text().splitlines()
    random.Random(3).shuffle(rows)                        # clocks out of order
    commands.write_text("\n".join([header, *rows]) + "\n")
    diagnosis = _diagnosis(damaged)
    assert any("1 row(s) with the wrong number of cells" in note for note in diagnosis.notes)
    assert (diagnosis.verdict, diagnosis.component) == ("fault", "flow_sensor")
    assert diagnosis.onset_s == pytest.approx(_diagnosis(bag).onset_s, abs=0.2)


def test_an_unreadable_clock_cell_is_counted_not_fatal(exported, tmp_path):
    _, folder = exported
    damaged = tmp_path / "flight"
    shutil.copytree(folder, damaged)
    flow = damaged / "flight-flow-velocity.csv"
    header, first, *rest = flow.read_text().splitlines()
    flow.write_text("\n".join([header, "x" + first[1:], *rest]) + "\n")
    signals = read_log(damaged, api.load_profile(None).sources)
    assert any("1 row(s) whose time does not read" in note for note in signals.notes)


def test_an_audit_root_holds_each_folder_as_one_log(exported, tmp_path, dive_cache,
                                                    profile):
    bag, folder = exported
    root = tmp_path / "flights"
    for name in ("a", "b"):
        copy = root / name
        shutil.copytree(folder, copy)
        for file in copy.iterdir():
            file.rename(copy / file.name.replace("flight-", f"{name}-"))
    shutil.copyfile(bag, root / "b" / "b.bag")           # the bag it was exported from
    dive = dive_cache(SCENARIO, SEED)                   # and an hour later, another flight
    write_log(replace(dive, start_ns=dive.start_ns + 3600 * 10**9), profile,
              root / "a" / "later.bag", "bag")
    found = discover([str(root)])
    # The bag a folder was exported from is the same flight: audited once, as the folder.
    assert sorted(p.relative_to(root).as_posix() for p in found.logs) == ["a", "a/later.bag",
                                                                         "b"]
    assert dict(found.skipped)[root / "b" / "b.bag"] == (
        "the same recording as the folder it lies in, b (100% of its time span on the same "
        "clock)")
    result = runner.invoke(app, ["audit", str(root), "--output", str(tmp_path / "audit"),
                                 "--jobs", "1", "--fail-on", "none"])
    assert result.exit_code == 0, result.output
    with (tmp_path / "audit" / "audit.csv").open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert sorted(row["format"] for row in rows) == ["bag", "topic-csv", "topic-csv"]
    assert all((row["verdict"], row["component"]) == ("fault", "flow_sensor") for row in rows)


@pytest.mark.shared_data("alfa")
@pytest.mark.parametrize("sequence", ALFA_WITH_BAGS)
def test_alfa_flights_read_the_same_from_bag_and_csv_folder(sequence):
    profile = api.load_profile("arduplane_carbonz")
    folder = ALFA / sequence
    from_csv = read_log(folder, profile.sources)
    from_bag = read_log(folder / f"{sequence}.bag", profile.sources)
    assert from_csv.format == "topic-csv" and from_bag.format == "bag"
    assert set(from_csv.series) == set(from_bag.series) == {
        *profile.command_names, *profile.sensor_names, *profile.input_names,
        *profile.output_names, CLOCK_REFERENCE}
    for name, series in from_bag.series.items():
        other = from_csv.series[name]
        assert np.array_equal(series.times_ns, other.times_ns), name
        np.testing.assert_allclose(other.values, series.values, rtol=1e-9, err_msg=name)
    assert abs(from_csv.start_ns - from_bag.start_ns) < 5_000_000


def _bag_without(source: Path, target: Path, topic: str) -> Path:
    """The bag's messages again, less those of ``topic``."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag1 import Writer

    with AnyReader([source]) as reader, Writer(target) as writer:
        kept = {c.id: writer.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data,
                                            md5sum=c.digest)
                for c in reader.connections if c.topic != topic}
        for connection, time_ns, raw in reader.messages():
            if connection.id in kept:
                writer.write(kept[connection.id], time_ns, raw)
    return target


@pytest.mark.shared_data("alfa")
def test_an_alfa_flight_without_its_airspeed_reads_with_the_input_held(tmp_path):
    """A flight recorded without the measured airspeed (an aircraft without the sensor, a
    recording that left the topic out) is read, not refused: the input is absent, so the
    model holds it at its typical value; everything else reads as from the whole flight."""
    from auvdiag_cli.engine.flat_signals import ABSENT
    from auvdiag_cli.engine.ingest import ingest

    profile = api.load_profile("arduplane_carbonz")
    sequence = ALFA_WITH_BAGS[0]
    folder = tmp_path / sequence
    folder.mkdir()
    for file in (ALFA / sequence).glob("*.csv"):
        if "nav_info-airspeed" not in file.name:
            (folder / file.name).symlink_to(file)
    bag = _bag_without(ALFA / sequence / f"{sequence}.bag", tmp_path / f"{sequence}.bag",
                       "/mavros/nav_info/airspeed")
    whole = ingest(ALFA / sequence, profile).frame
    for log in (folder, bag):
        frame = ingest(log, profile).frame
        assert frame.flat_inputs == {"airspeed": ABSENT}, log
        airspeed = np.array([n == "airspeed" for n in frame.input_names])
        assert not frame.inputs[:, airspeed].any() and whole.inputs[:, airspeed].any()
        np.testing.assert_allclose(frame.inputs[:, ~airspeed], whole.inputs[:, ~airspeed],
                                   err_msg=str(log))     # the other inputs as before
        assert any(note.startswith("airspeed is not in this log") for note in frame.notes)
        np.testing.assert_allclose(frame.sensors, whole.sensors, rtol=1e-9, err_msg=str(log))
    result = runner.invoke(app, ["inspect", str(folder), "--profile", "arduplane_carbonz"])
    assert result.exit_code == 0, result.output
    assert "absent   airspeed" in result.output and "MISSING" not in result.output
    # A signal the model is judged on is still required.
    (folder / next(f.name for f in folder.iterdir() if "vfr_hud" in f.name)).unlink()
    with pytest.raises(LogError, match=r"missing topic.*vfr_hud"):
        ingest(folder, profile)


@pytest.mark.shared_data("alfa")
def test_alfa_labels_name_folders_that_read():
    with (ALFA / "labels.csv").open(newline="") as stream:
        sequences = [row["sequence"] for row in csv.DictReader(stream)]
    assert len(sequences) >= 20
    assert all(detect_format(ALFA / s) == "topic-csv" for s in sequences)
    result = runner.invoke(app, ["inspect", str(ALFA / sequences[1]), "--profile",
                                 "arduplane_carbonz"])
    assert result.exit_code == 0, result.output
    assert "MISSING" not in result.output and json.dumps("topic-csv")[1:-1] in result.output


def test_report_times_line_up_with_other_records_in_utc(exported):
    from datetime import datetime, timedelta

    _, folder = exported
    _, report = diagnose_json(folder)
    start = datetime.fromisoformat(report["start_time_utc"])
    assert report["start_time_utc"].endswith("+00:00") and "." in report["start_time_utc"]
    for seconds, utc in ((report["onset_s"], report["onset_utc"]),
                         (report["detected_at_s"], report["detected_at_utc"])):
        assert datetime.fromisoformat(utc) - start == pytest.approx(
            timedelta(seconds=seconds), abs=timedelta(milliseconds=1))


def test_a_part_of_a_time_reads_from_the_time_rostopic_writes_whole(tmp_path):
    """rostopic writes a ROS time as one column of nanoseconds; a profile names its parts
    as a bag holds them (``header.stamp.sec``, ``nanosec``), and reads them from either."""
    folder = tmp_path / "rec"
    folder.mkdir()
    (folder / "rec-gps-time.csv").write_text(
        "%time,field.header.stamp,field.time_ref\n"
        "1532133199412325200,1532133199411901392,1532982290839000000\n"
        "1532133199916705840,1532133199916312144,1532982291341000000\n")
    sources = LogSources({name: FieldSource("/gps/time", path) for name, path in (
        ("seconds", "time_ref.sec"), ("nanoseconds", "time_ref.nanosec"),
        ("stamp", "header.stamp.secs"))})
    series = read_log(folder, {"ros": sources}).series
    assert series["seconds"].values.tolist() == [1532982290.0, 1532982291.0]
    np.testing.assert_allclose(series["nanoseconds"].values, [839e6, 341e6], atol=512)
    assert series["stamp"].values.tolist() == [1532133199.0, 1532133199.0]


def test_a_stray_quote_ends_that_topic_as_damage_not_a_crash(exported, tmp_path):
    """A quote the recorder never wrote runs the rest of the file into one field past the
    csv module's limit (found by the fuzzer): the topic is read up to it."""
    _, folder = exported
    damaged = tmp_path / "flight"
    shutil.copytree(folder, damaged)
    commands = damaged / "flight-thrusters-command.csv"
    lines = commands.read_text().splitlines()
    cut = len(lines) * 3 // 4
    filler = [lines[-1]] * (200_000 // len(lines[-1]))   # more than the limit after it
    commands.write_text("\n".join([*lines[:cut], '"' + lines[cut], *filler]) + "\n")
    _, report = diagnose_json(damaged)
    assert report["completeness"]["status"] == "partial"
    assert "flight-thrusters-command.csv: unreadable from line" in (
        report["completeness"]["reason"])


@pytest.mark.shared_data("alfa")
def test_a_profile_drafted_from_an_alfa_folder_takes_set_points_as_set_points(tmp_path):
    from auvdiag_cli.vehicle.profile import load_profile

    folder = next(p for p in sorted(ALFA.iterdir()) if p.is_dir())
    drafted = tmp_path / "plane.toml"
    result = runner.invoke(app, ["init-profile", str(folder), "--output", str(drafted)])
    assert result.exit_code == 0, result.output
    profile = load_profile(drafted)
    assert {"roll_commanded", "pitch_commanded"} <= set(profile.command_names)
    assert all(c.kind == "set_point" for c in profile.commands)
    assert "throttle" in profile.output_names      # read for the effort check only
    assert not any(set(g.members) & {c.name for c in profile.commands
                                     if c.kind == "set_point"} for g in profile.effort_groups)
    # The autopilot's GPS time the flight carries: it dates a log whose own clock is off.
    reference = profile.sources["ros"].signals[CLOCK_REFERENCE]
    assert (reference.topic, reference.field) == ("/mavros/time_reference", "time_ref.sec")
