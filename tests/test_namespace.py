"""A vehicle launched under a ROS namespace: its topics are found under it, the namespace
names the vehicle in a fleet, and a log holding two vehicles is refused unless the profile
names one. Logs are written by the real writers (rosbags, mcap)."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers import assert_same_signals, diagnose_json
from typer.testing import CliRunner

from adapters import read_log
from adapters.identity import log_identity
from adapters.namespace import ROOT, normalised, resolve
from auvdiag_cli import api
from auvdiag_cli.cli import app
from auvdiag_cli.simulator.writers import ExtraTopic, write_log
from auvdiag_cli.simulator.writers.ros import RosMessages, ros_topics
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import LogError

ROS_FORMATS = ("bag", "db3", "ros2-mcap", "mcap")


def _write(dive, profile: Profile, path: Path, fmt: str, namespace: str,
           also: str | None = None) -> Path:
    """The dive written under ``namespace``; ``also``: a second vehicle's topics (one zero
    message each) under that namespace in the same log."""
    extra = []
    if also is not None:
        builder = RosMessages(fmt == "bag", {})
        for topic, msgtype in ros_topics(profile).items():
            start = dive.start_ns

            def build(types, index, msgtype=msgtype):
                message = builder.zero(msgtype)
                if msgtype.endswith("MultiArray"):
                    message.data = np.zeros(4)          # one command per thruster
                return message

            extra.append(ExtraTopic(f"{also}{topic}", msgtype, [start], build))
    write_log(dive, profile, path, fmt, extra, namespace)
    return path


def test_the_namespace_is_the_one_holding_most_of_the_profiles_topics(tmp_path):
    wanted = {"/thrusters/command", "/imu/data", "/tf"}
    at_root = {"/thrusters/command", "/imu/data", "/tf", "/rosout"}
    assert resolve(tmp_path, wanted, at_root).namespace == ROOT
    moved = {"/rov2/thrusters/command", "/rov2/imu/data", "/tf", "/rov2/tf_other"}
    found = resolve(tmp_path, wanted, moved)
    assert found.namespace == "/rov2"
    assert found.names == {"/thrusters/command": "/rov2/thrusters/command",
                           "/imu/data": "/rov2/imu/data", "/tf": "/tf"}     # global stays
    deep = {"/fleet/a/thrusters/command", "/fleet/a/imu/data"}
    assert resolve(tmp_path, wanted, deep).namespace == "/fleet/a"
    assert resolve(tmp_path, wanted, {"/rov2/imu/data"}).namespace == "/rov2"
    # One topic under a namespace does not outweigh two at the root.
    assert resolve(tmp_path, wanted, {"/thrusters/command", "/imu/data",
                                      "/x/tf"}).namespace == ROOT
    both = moved | {"/rov1/thrusters/command", "/rov1/imu/data"}
    with pytest.raises(LogError, match=r"2 namespaces \(/rov1, /rov2\).*namespace = \"/rov1\""):
        resolve(tmp_path, wanted, both)
    assert resolve(tmp_path, wanted, both, "rov1/").names["/imu/data"] == "/rov1/imu/data"
    assert [normalised(n) for n in ("", "/", "a", "/a/b/")] == ["", "", "/a", "/a/b"]


@pytest.mark.parametrize("fmt", ROS_FORMATS)
def test_a_namespaced_log_reads_as_the_same_dive(fmt, tmp_path, dive_cache, profile, make_log):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / f"rov2.{fmt}", fmt, "/rov2")
    read = read_log(log, profile.sources)
    reference = read_log(make_log("paper-normal", 11, fmt), profile.sources)
    assert_same_signals(read, reference)
    assert read.namespace == "/rov2" and reference.namespace == ROOT
    assert "topics read under the namespace /rov2" in read.notes
    said = log_identity(log, fmt, profile.sources["ros"].topics)
    assert said is not None and said.vehicle == "ros-rov2" and said.distinctive
    assert log_identity(make_log("paper-normal", 11, fmt), fmt,
                        profile.sources["ros"].topics) is None


@pytest.mark.parametrize("fmt", ("bag", "mcap"))
def test_a_damaged_namespaced_log_is_read_under_its_namespace(fmt, tmp_path, dive_cache,
                                                               profile):
    """Without an index the topics are met as the file is read: the namespace too."""
    whole = _write(dive_cache("paper-normal", 11), profile, tmp_path / f"whole.{fmt}", fmt,
                   "/rov2")
    cut = tmp_path / f"cut.{fmt}"
    cut.write_bytes(whole.read_bytes()[:int(whole.stat().st_size * 0.7)])
    read = read_log(cut, profile.sources)
    assert read.namespace == "/rov2" and read.damage is not None
    assert len(read.series["flow"]) > 0


def test_two_vehicles_in_one_log_are_refused_unless_the_profile_names_one(
        tmp_path, dive_cache, profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / "two.mcap", "mcap", "/rov2", also="/rov1")
    with pytest.raises(LogError, match=r"two.mcap: .*namespaces \(/rov1, /rov2\)"):
        read_log(log, profile.sources)
    assert log_identity(log, "mcap", profile.sources["ros"].topics) is None
    chosen = {**profile.sources, "ros": replace(profile.sources["ros"], namespace="/rov2")}
    rov2 = read_log(log, chosen)
    assert rov2.namespace == "/rov2" and len(rov2.series["flow"]) > 1000
    one_message = {**profile.sources, "ros": replace(profile.sources["ros"], namespace="rov1")}
    assert len(read_log(log, one_message).series["flow"]) == 1
    said = log_identity(log, "mcap", profile.sources["ros"].topics, "/rov1")
    assert said is not None and said.vehicle == "ros-rov1"


def test_a_fleet_folder_of_namespaced_logs_trends_per_vehicle(tmp_path, dive_cache, profile):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    for namespace in ("/rovA", "/rovB"):
        for seed in (11, 12):
            _write(dive_cache("paper-normal", seed), profile,
                   fleet / f"{namespace[1:]}-{seed}.mcap", "mcap", namespace)
    result = api.audit([fleet], None, None, tmp_path / "out")
    assert {r.fleet_vehicle for r in result.records} == {"ros-rovA", "ros-rovB"}
    assert all(r.verdict == "normal" for r in result.records), [r.error for r in result.records]
    assert api.trend(tmp_path / "out").short == {"ros-rovA": 2, "ros-rovB": 2}


def test_a_vehicle_simulated_under_a_namespace_diagnoses_as_at_the_root(tmp_path):
    log = tmp_path / "rov2.bag"
    made = CliRunner().invoke(app, ["simulate", "paper-normal", "--format", "bag",
                                    "--namespace", "rov2", "--output", str(log)])
    assert made.exit_code == 0, made.output
    status, report = diagnose_json(log)
    assert status == 0 and report["verdict"] == "normal"
    assert "topics read under the namespace /rov2" in report["notes"]
