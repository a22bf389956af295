"""Which vehicle of a fleet a log is: the log's own word (MAVLink system id and board id,
DataFlash SYSID_THISMAV), else `--vehicle-from`; the trend and the table go per vehicle."""

import shutil
import struct
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from shared_data import SHARED_DATA

from adapters.identity import log_identity
from auvdiag_cli import api
from auvdiag_cli.audit.fleet_vehicle import VehicleRule
from auvdiag_errors import UsageError

SAMPLES = Path(__file__).resolve().parents[1] / "sample_logs"


def _tlog(path: Path, system: int, uid: int | None) -> Path:
    """A ground station's heartbeat, then the vehicle's, as a telemetry log records them."""
    frames = []
    station = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    frames.append(station.heartbeat_encode(6, 8, 0, 0, 0).pack(station))
    vehicle = mavlink.MAVLink(None, srcSystem=system, srcComponent=1)
    frames.append(vehicle.heartbeat_encode(12, 3, 0, 0, 4).pack(vehicle))
    if uid is not None:
        frames.append(vehicle.autopilot_version_encode(
            0, 0, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, uid).pack(vehicle))
    path.write_bytes(b"".join(struct.pack(">Q", 1_700_000_000_000_000 + k) + bytes(frame)
                              for k, frame in enumerate(frames)))
    return path


def test_a_telemetry_log_names_its_vehicle_not_the_ground_station(tmp_path):
    said = log_identity(_tlog(tmp_path / "a.tlog", 7, None), "tlog")
    assert said is not None and said.vehicle == "mavlink-7" and said.distinctive
    assert "MAV_TYPE 12" in said.evidence
    board = log_identity(_tlog(tmp_path / "b.tlog", 1, 0x3D0041), "tlog")
    assert board is not None and board.vehicle == "mavlink-1-uid-00000000003d0041"
    assert board.distinctive
    default = log_identity(_tlog(tmp_path / "c.tlog", 1, None), "tlog")
    assert default is not None and not default.distinctive     # every autopilot's default
    assert log_identity(tmp_path / "a.tlog", "mcap") is None
    (tmp_path / "cut.tlog").write_bytes((tmp_path / "a.tlog").read_bytes()[:30])
    assert log_identity(tmp_path / "cut.tlog", "tlog") is None


def test_a_default_system_id_falls_back_to_the_folder(tmp_path):
    (tmp_path / "rov-a").mkdir()
    rule = VehicleRule.parse("log")
    assert rule.vehicle_of(_tlog(tmp_path / "rov-a" / "d.tlog", 1, None)).vehicle == "rov-a"
    named = rule.vehicle_of(_tlog(tmp_path / "rov-a" / "e.tlog", 4, None))
    assert named.vehicle == "mavlink-4" and named.source.startswith("log: HEARTBEAT")


def test_the_rules_and_their_errors(tmp_path):
    log = tmp_path / "fleet" / "rovB_2026-11-20.mcap"
    assert VehicleRule.parse("regex:^(rov[A-Z])_").vehicle_of(log).vehicle == "rovB"
    assert VehicleRule.parse("regex:^x").vehicle_of(log).vehicle == "fleet"
    assert VehicleRule.parse("folder").vehicle_of(log).vehicle == "fleet"
    mapping = tmp_path / "map.csv"
    mapping.write_text("log,vehicle\nrovB_2026-11-20.mcap,hull-12\n")
    assert VehicleRule.parse(f"csv:{mapping}").vehicle_of(log).vehicle == "hull-12"
    for bad in ("regex:(", "csv:", "serial", f"csv:{tmp_path / 'none.csv'}"):
        with pytest.raises(UsageError, match="vehicle"):
            VehicleRule.parse(bad)


@pytest.mark.shared_data("ardusub/small.BIN")
def test_the_real_ardusub_logs_carry_the_default_system_id():
    for name, fmt, evidence in (("small.BIN", "bin", "PARM SYSID_THISMAV = 1"),
                                ("small.tlog", "tlog", "HEARTBEAT: system 1, MAV_TYPE 12")):
        said = log_identity(SHARED_DATA / "ardusub" / name, fmt)
        assert said is not None and said.evidence == evidence and not said.distinctive


def test_two_vehicles_in_one_folder_trend_apart(tmp_path):
    fleet = tmp_path / "fleet"
    fleet.mkdir()
    for vehicle in ("rovA", "rovB"):
        for number, sample in enumerate(("mission-large-cw.mcap", "mission-thruster-1-dead.mcap")):
            shutil.copy(SAMPLES / sample, fleet / f"{vehicle}-{number}.mcap")
    result = api.audit([fleet], None, None, tmp_path / "out", vehicle_from=r"regex:^(rov\w)-")
    assert {r.fleet_vehicle for r in result.records} == {"rovA", "rovB"}
    assert api.trend(tmp_path / "out").short == {"rovA": 2, "rovB": 2}
    table = (tmp_path / "out" / "audit.csv").read_text().splitlines()
    assert "fleet_vehicle" in table[0] and sum("rovA" in row for row in table[1:]) == 2
    # Reused, re-assigned:
    again = api.audit([fleet], None, None, tmp_path / "out", vehicle_from="folder")
    assert again.reused == 4 and api.trend(tmp_path / "out").short == {"fleet": 4}


def _ulog(path: Path, system: str, info: dict[str, str] | None = None) -> Path:
    import numpy as np

    from auvdiag_cli.simulator.writers.ulog import UlogTopic, write_ulog_file

    topic = UlogTopic("actuator_motors", ("control[0]",), np.arange(10) * 10_000,
                      np.zeros((10, 1)))
    write_ulog_file(path, [topic], 0, system=system, info=info)
    return path


def test_a_ulog_names_its_vehicle_by_board_id_else_by_a_name_someone_gave_it(tmp_path):
    from pyulog import ULog

    named = _ulog(tmp_path / "named.ulg", "auv-7")
    assert ULog(str(named)).msg_info_dict["sys_name"] == "auv-7"     # what PX4 tools read
    said = log_identity(named, "ulog")
    assert said is not None and said.vehicle == "ulog-auv-7" and said.distinctive
    board = log_identity(_ulog(tmp_path / "board.ulg", "PX4", {"sys_uuid": "0001a2b3"}),
                         "ulog")
    assert board is not None and board.vehicle == "ulog-PX4-uid-0001a2b3" and board.distinctive
    default = log_identity(_ulog(tmp_path / "default.ulg", "PX4"), "ulog")
    assert default is not None and not default.distinctive          # PX4's factory name
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(named.read_bytes()[:20])
    assert log_identity(cut, "ulog") is None
