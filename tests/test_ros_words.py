"""A ROS vehicle's own words: its nodes' `/rosout` log messages (ROS 1 and ROS 2 levels) and
its autopilot's status texts as mavros republishes them, read from every ROS log format as
the real writers (rosbags, mcap, a `rostopic echo -p` export) write them, and lined up with
the diagnosis like ArduPilot's own texts."""

import json
from pathlib import Path

import pytest
from helpers import diagnose_json
from typer.testing import CliRunner

from adapters import inventory, read_log
from adapters.ros_words import ROSOUT, STATUSTEXT, WordsRead, severity
from auvdiag_cli.cli import app
from auvdiag_cli.engine.autopilot_words import is_alarm, said_in
from auvdiag_cli.fuzz.mutations import mutate
from auvdiag_cli.simulator.writers import ROS1_FORMATS, ExtraTopic, write_log
from auvdiag_cli.simulator.writers.ros import hardware_status, node_log, status_texts
from auvdiag_errors import LogError

ROS_FORMATS = ("bag", "db3", "ros2-mcap", "mcap", "topic-csv")
# (seconds into the dive, ROS 1 level, node, text)
NODE_SAYS = ((5.0, 2, "/mission", "starting the mission"),
             (20.0, 4, "/robot_state_publisher", "TF_REPEATED_DATA ignoring data"),
             (30.0, 4, "/dvl_driver", "DVL lost bottom lock"),
             (31.0, 4, "/dvl_driver", "DVL lost bottom lock"),
             (40.0, 8, "/thruster_driver", "thruster 2 not responding"),
             (45.0, 1, "/thruster_driver", "debug counter 12"))
AUTOPILOT_SAYS = ((12.0, 6, "Mission: 1 WP"), (50.0, 2, "Leak Detected"))
# As read: (whole seconds into the log, "node: text", MAVLink severity).
NODE_WORDS = [(5, "/mission: starting the mission", 6),
              (20, "/robot_state_publisher: TF_REPEATED_DATA ignoring data", None),
              (30, "/dvl_driver: DVL lost bottom lock", None),
              (31, "/dvl_driver: DVL lost bottom lock", None),
              (40, "/thruster_driver: thruster 2 not responding", 3),
              (45, "/thruster_driver: debug counter 12", 7)]


def _node_log(start_ns: int, ros1: bool, topic: str = "/rosout") -> ExtraTopic:
    return node_log(topic, ros1, [(start_ns + int(at_s * 1e9), level, node, text)
                                  for at_s, level, node, text in NODE_SAYS])


def _status_texts(start_ns: int, ros1: bool, namespace: str = "") -> ExtraTopic:
    return status_texts(f"{namespace}/mavros/statustext/recv", ros1,
                        [(start_ns + int(at_s * 1e9), level, text)
                         for at_s, level, text in AUTOPILOT_SAYS])


def _write(dive, profile, path: Path, fmt: str, extra_of, namespace: str = "") -> Path:
    ros1 = fmt in ROS1_FORMATS
    write_log(dive, profile, path, fmt, extra_of(dive.start_ns, ros1), namespace)
    return path


def _said(signals) -> list[tuple[float, str, int | None]]:
    return [(round((m.time_ns - signals.start_ns) / 1e9), m.text, m.severity)
            for m in signals.autopilot_messages]


@pytest.mark.parametrize("fmt", ROS_FORMATS)
def test_node_and_autopilot_words_read_from_every_ros_format(fmt, tmp_path, dive_cache,
                                                              profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / f"said.{fmt}", fmt,
                 lambda start, ros1: [_node_log(start, ros1), _status_texts(start, ros1)])
    read = read_log(log, profile.sources)
    plain = read_log(_write(dive, profile, tmp_path / f"plain.{fmt}", fmt,
                            lambda start, ros1: []), profile.sources)
    assert _said(plain) == [] and read.messages_read == plain.messages_read
    assert _said(read) == sorted([*NODE_WORDS, (12, "Mission: 1 WP", 6),
                                  (50, "Leak Detected", 2)])
    # A node's WARN is trouble only where its words say so; ERROR and the autopilot's
    # CRITICAL are; the routine transform warning, INFO and DEBUG are not.
    said = said_in(read.autopilot_messages, read.start_ns, lambda at_s: True)
    assert said is not None
    assert [(a.text, a.times) for a in said.alarms] == [
        ("/dvl_driver: DVL lost bottom lock", 2),
        ("/thruster_driver: thruster 2 not responding", 1), ("Leak Detected", 1)]
    assert said.other_messages == 4


def test_rosout_aggregated_is_read_only_where_rosout_is_not(tmp_path, dive_cache, profile):
    dive = dive_cache("paper-normal", 11)
    both = read_log(_write(dive, profile, tmp_path / "both.bag", "bag", lambda start, ros1: [
        _node_log(start, ros1), _node_log(start, ros1, "/rosout_agg")]), profile.sources)
    assert len(both.autopilot_messages) == len(NODE_SAYS)
    only = read_log(_write(dive, profile, tmp_path / "agg.bag", "bag", lambda start, ros1: [
        _node_log(start, ros1, "/rosout_agg")]), profile.sources)
    assert _said(only) == _said(both)


def test_status_texts_are_read_under_the_vehicles_namespace(tmp_path, dive_cache, profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / "rov2.bag", "bag", lambda start, ros1: [
        _node_log(start, ros1), _status_texts(start, ros1, "/rov2")], "/rov2")
    read = read_log(log, profile.sources)
    assert read.namespace == "/rov2"
    texts = [m.text for m in read.autopilot_messages]
    assert "Leak Detected" in texts and "/dvl_driver: DVL lost bottom lock" in texts


def test_a_rosout_of_another_type_says_nothing_and_the_log_still_reads(tmp_path, dive_cache,
                                                                       profile):
    dive = dive_cache("paper-normal", 11)

    def strings(start, ros1):
        return [ExtraTopic("/rosout", "std_msgs/msg/String", [start + 10**9],
                           lambda types, index: types["std_msgs/msg/String"](data="hello"))]

    read = read_log(_write(dive, profile, tmp_path / "odd.bag", "bag", strings),
                    profile.sources)
    assert read.autopilot_messages == [] and read.series


def test_levels_map_to_mavlink_severities():
    assert [severity(ROSOUT, level) for level in (1, 2, 4, 8, 16)] == [7, 6, None, 3, 2]
    assert [severity(ROSOUT, level) for level in (10, 20, 30, 40, 50)] == [7, 6, None, 3, 2]
    assert [severity(ROSOUT, level) for level in (0, 3, "x", None, float("inf"),
                                                  float("nan"))] == [None] * 6
    assert [severity(STATUSTEXT, level) for level in (0, 4, 7, 8)] == [0, 4, 7, None]
    words = WordsRead()
    words.add(ROSOUT, 5, b"thruster 1 overheating\0junk", 8, b"/esc\0")
    words.add(ROSOUT, 1, "   ", 8, "/esc")                # nothing said
    assert [(m.text, m.severity) for m in words.messages()] == [
        ("/esc: thruster 1 overheating", 3)]
    assert is_alarm(words.messages()[0])


def test_a_normal_dive_says_what_the_vehicle_reported_beside_its_verdict(
        tmp_path, dive_cache, profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / "said.bag", "bag", lambda start, ros1: [
        _node_log(start, ros1), _status_texts(start, ros1), _hardware(start, ros1)])
    status, report = diagnose_json(log)
    assert status == 0 and report["verdict"] == "normal", json.dumps(report)[:400]
    part = report["autopilot"]
    assert part["summary"].startswith("reported trouble this diagnosis did not find: "
                                      '"/dvl_driver: DVL lost bottom lock"')
    assert part["summary"].endswith('; already so when the log began: '
                                    '"mavros: Battery: Low voltage"')
    assert [a["text"] for a in part["alarms"]] == [
        "/dvl_driver: DVL lost bottom lock", "dvl: status: bottom lock lost",
        "/thruster_driver: thruster 2 not responding", "dvl: status: no data",
        "Leak Detected", "thrusters: stale"]
    assert [(a["text"], a["first_s"]) for a in part["standing"]] == [
        ("mavros: Battery: Low voltage", 0.0)]


@pytest.mark.parametrize("fmt", ("bag", "ros2-mcap"))
def test_a_log_cut_short_keeps_the_words_before_the_damage(fmt, tmp_path, dive_cache,
                                                           profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / f"said.{fmt}", fmt,
                 lambda start, ros1: [_node_log(start, ros1)])
    storage = next(log.glob("*.mcap")) if log.is_dir() else log
    data = storage.read_bytes()
    storage.write_bytes(data[:len(data) * 2 // 3])
    read = read_log(log, profile.sources)
    assert read.damage is not None
    said = _said(read)
    assert said and said == NODE_WORDS[:len(said)]
    assert max(at for at, _, _ in said) <= (read.end_ns - read.start_ns) / 1e9 + 1


def test_inspect_quotes_what_the_vehicle_said_under_its_namespace(tmp_path, dive_cache,
                                                                   profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / "rov2.db3", "db3", lambda start, ros1: [
        _node_log(start, ros1), _status_texts(start, ros1, "/rov2")], "/rov2")
    shown = CliRunner().invoke(app, ["inspect", str(log)])
    assert shown.exit_code == 0, shown.output
    assert ('  autopilot reported trouble: "/dvl_driver: DVL lost bottom lock" at 30.0 s, '
            '2 times to 31.0 s; "/thruster_driver: thruster 2 not responding" at 40.0 s; '
            '"Leak Detected" at 50.0 s') in shown.output
    standing = _write(dive, profile, tmp_path / "standing.db3", "db3",
                      lambda start, ros1: [_hardware(start, ros1)])
    shown = CliRunner().invoke(app, ["inspect", str(standing)])
    assert ('reported trouble: "dvl: status: bottom lock lost" at 30.0 s; "dvl: status: no '
            'data" at 40.0 s; "thrusters: stale" at 60.0 s; already so when the log began: '
            '"mavros: Battery: Low voltage"') in shown.output


@pytest.mark.parametrize(("fmt", "stored", "said"), [
    ("db3", "*.db3", b"thruster 2 not responding"), ("db3", "*.db3", b"bottom lock lost"),
    ("topic-csv", "*-rosout.csv", b"thruster 2 not responding"),
    ("topic-csv", "*-diagnostics.csv", b"bottom lock lost")])
def test_damage_where_the_words_lie_is_read_or_refused_as_a_log_error(
        fmt, stored, said, tmp_path, dive_cache, profile):
    # Where the words are stored as they are (not in compressed chunks, which the format
    # campaigns damage whole).
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / f"said.{fmt}", fmt, lambda start, ros1: [
        _node_log(start, ros1), _status_texts(start, ros1), _hardware(start, ros1)])
    storage = next(log.glob(stored))
    whole = storage.read_bytes()
    at = whole.find(said)
    assert at > 0
    low, high = max(0, at - 512), at + 512
    outcomes = {"read": 0, "refused": 0}
    for seed in range(100):
        damaged, _ = mutate(whole[low:high], seed)
        storage.write_bytes(whole[:low] + damaged + whole[high:])
        try:
            inventory(log)
            read_log(log, profile.sources)
            outcomes["read"] += 1
        except LogError as error:
            assert "\n" not in str(error) and str(log) in str(error)
            outcomes["refused"] += 1
    assert outcomes["read"] > 0, outcomes


def _hardware(start_ns: int, ros1: bool, topic: str = "/diagnostics") -> ExtraTopic:
    """A battery monitor warning all along (set up wrong), and a DVL whose status worsens
    at 30 s and 40 s and recovers at 50 s; the thrusters' driver falls silent at 60 s."""
    def statuses(at_s: float) -> list[tuple[int, str, str]]:
        dvl = ((0, "no fault") if at_s < 30 or at_s >= 50 else
               (1, "bottom lock lost") if at_s < 40 else (2, "no data"))
        return [(1, "mavros: Battery", "Low voltage"), (dvl[0], "dvl: status", dvl[1]),
                *([(0, "thrusters", "ok")] if at_s < 60 else [(3, "thrusters", "stale")])]

    return hardware_status(topic, ros1, [(start_ns + int(at_s * 1e9), statuses(at_s))
                                         for at_s in range(0, 70)])


HARDWARE_WORDS = [(30, "dvl: status: bottom lock lost", None), (40, "dvl: status: no data", 3),
                  (60, "thrusters: stale", 4)]


@pytest.mark.parametrize("fmt", ROS_FORMATS)
def test_a_hardware_status_that_worsens_is_news_one_that_stands_is_not(fmt, tmp_path,
                                                                       dive_cache, profile):
    dive = dive_cache("paper-normal", 11)
    log = _write(dive, profile, tmp_path / f"hw.{fmt}", fmt,
                 lambda start, ros1: [_hardware(start, ros1)])
    read = read_log(log, profile.sources)
    assert _said(read) == [(0, "mavros: Battery: Low voltage", None), *HARDWARE_WORDS]
    said = said_in(read.autopilot_messages, read.start_ns, lambda at_s: at_s > 10)
    assert said is not None and [a.text for a in said.alarms] == [
        "dvl: status: bottom lock lost", "dvl: status: no data", "thrusters: stale"]
    # The battery monitor's warning stands from the first report, operating or not.
    assert [(a.text, a.first_s) for a in said.standing] == [
        ("mavros: Battery: Low voltage", 0.0)]
    assert said.describe(False, None).endswith(
        '; already so when the log began: "mavros: Battery: Low voltage"')


def test_the_aggregated_statuses_are_read_only_where_the_plain_ones_are_not(
        tmp_path, dive_cache, profile):
    dive = dive_cache("paper-normal", 11)
    both = read_log(_write(dive, profile, tmp_path / "both.bag", "bag", lambda start, ros1: [
        _hardware(start, ros1), _hardware(start, ros1, "/diagnostics_agg")]), profile.sources)
    only = read_log(_write(dive, profile, tmp_path / "agg.bag", "bag", lambda start, ros1: [
        _hardware(start, ros1, "/diagnostics_agg")]), profile.sources)
    assert _said(both) == _said(only) == [(0, "mavros: Battery: Low voltage", None),
                                          *HARDWARE_WORDS]
