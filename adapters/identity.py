"""Which vehicle wrote a log, where the log itself says so: a MAVLink telemetry log's
autopilot (its system id and vehicle type, from HEARTBEAT; the flight controller's unique
id from AUTOPILOT_VERSION where it is sent), a DataFlash log's SYSID_THISMAV parameter,
a ULog's information messages (``sys_uuid``, else ``sys_name``), a MOOS alog's community
(the app name its MOOSDB posts under), and the ROS namespace a bag's or an MCAP's topics
are under. Nothing here raises on a damaged log: what cannot be
read says nothing."""

import re
import struct
from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path

from adapters import inventory
from adapters.autopilot_setup import TlogPayloads, autopilot_heartbeats, dataflash_parameters
from adapters.compressed import first_bytes
from adapters.mavlink_scan import (
    RecordIndex,
    index_dataflash,
    index_tlog,
)
from adapters.mcap import summary_topics
from adapters.namespace import resolve
from adapters.recognise import bag_storages
from adapters.rosbag import bag_topics
from adapters.rosbag2_sqlite import db3_topics
from auvdiag_errors import LogError

AUTOPILOT_VERSION = 148
BOARD_UID_END = 16             # AUTOPILOT_VERSION's uid: payload bytes 8-15
# Autopilots send HEARTBEAT and AUTOPILOT_VERSION, and write their parameters, as a log
# begins: its first bytes say who wrote it, and an audit does not walk every log twice.
PREFIX_BYTES = 2 << 20


DEFAULT_SYSTEM_ID = 1          # ArduPilot's and PX4's default: names no vehicle in a fleet
DEFAULT_ULOG_NAME = "PX4"      # PX4's sys_name unless someone named the vehicle
ULOG_HEADER_BYTES = 16
ULOG_INFO = ord("I")
ULOG_DATA_BEGINS = b"ALCD"     # subscriptions, text and data end the definitions
# A MOOSDB posts its own variables (DB_TIME, DB_UPTIME, DB_CLIENTS) as MOOSDB_<community>:
# MOOS-IvP names a vehicle's community after the vehicle. "#1" is MOOS's default.
MOOSDB_POSTING = re.compile(rb"^[ \t]*[0-9.]+[ \t]+DB_[A-Z_]+[ \t]+MOOSDB_([^ \t\r\n]+)",
                            re.MULTILINE)
DEFAULT_COMMUNITY = "#1"


@dataclass(frozen=True)
class LogIdentity:
    vehicle: str       # what the fleet calls it: "mavlink-7", "mavlink-1-uid-3d0041…"
    evidence: str      # where in the log it was read

    @property
    def distinctive(self) -> bool:
        """Whether it tells this vehicle from others: a board's unique id, or a system id or
        name someone set (every autopilot leaves the factory as system 1, and PX4 as "PX4")."""
        return "-uid-" in self.vehicle or self.vehicle not in (
            f"mavlink-{DEFAULT_SYSTEM_ID}", f"ulog-{DEFAULT_ULOG_NAME}",
            f"moos-{DEFAULT_COMMUNITY}")


ROS_FORMATS = ("bag", "db3", "ros2-mcap", "mcap")


def log_identity(path: Path, log_format: str, ros_topics: Collection[str] = (),
                 namespace: str | None = None) -> LogIdentity | None:
    """The vehicle the log names, or None where it names none (or cannot be read).
    ``ros_topics``: the profile's ROS topics, whose namespace in a ROS log or MCAP names
    the vehicle (``namespace``: the one the profile fixes, else found)."""
    if log_format in ROS_FORMATS:
        return _namespace_identity(path, log_format, ros_topics, namespace)
    if log_format not in ("tlog", "bin", "ulog", "alog"):
        return None
    try:
        prefix = first_bytes(path, PREFIX_BYTES)        # an `.alog.gz` decompressed
        if log_format == "alog":
            return _moos_identity(prefix)
        if log_format == "tlog":
            return _tlog_identity(index_tlog(prefix, {}))
        if log_format == "ulog":
            return _ulog_identity(_ulog_info(prefix))
        return _dataflash_identity(index_dataflash(prefix))
    except (OSError, ValueError, IndexError, struct.error):
        return None


def _tlog_identity(index: RecordIndex) -> LogIdentity | None:
    vehicles = autopilot_heartbeats(index)
    if not vehicles:
        return None
    (sysid, mav_type), _ = vehicles.most_common(1)[0]
    name, evidence = f"mavlink-{sysid}", f"HEARTBEAT: system {sysid}, MAV_TYPE {mav_type}"
    uid = _board_uid(index, sysid)
    if uid:
        name, evidence = f"{name}-uid-{uid}", f"{evidence}; AUTOPILOT_VERSION uid {uid}"
    return LogIdentity(name, evidence)


def _board_uid(index: RecordIndex, sysid: int) -> str | None:
    """AUTOPILOT_VERSION's 64-bit uid (bytes 8-15 of the payload), where non-zero."""
    for sender, payload in TlogPayloads(index).of(AUTOPILOT_VERSION, BOARD_UID_END):
        uid = int.from_bytes(payload[8:BOARD_UID_END], "little")
        if sender == sysid and uid:
            return f"{uid:016x}"
    return None


def _dataflash_identity(index: RecordIndex) -> LogIdentity | None:
    value = dataflash_parameters(index).get("SYSID_THISMAV")
    if value is None:
        return None
    return LogIdentity(f"mavlink-{int(value)}", f"PARM SYSID_THISMAV = {int(value)}")


def _ulog_info(prefix: bytes) -> dict[str, bytes]:
    """The information messages ('I': "type name" and value) of a ULog's definitions."""
    info, at = {}, ULOG_HEADER_BYTES
    while at + 3 <= len(prefix):
        length, kind = struct.unpack_from("<HB", prefix, at)
        body = prefix[at + 3:at + 3 + length]
        if kind in ULOG_DATA_BEGINS or length == 0 or len(body) < length:
            break
        if kind == ULOG_INFO and body and 1 + body[0] <= length:
            key = body[1:1 + body[0]].decode("ascii", "replace").split(" ")[-1]
            info[key] = body[1 + body[0]:]
        at += 3 + length
    return info


def _ulog_identity(info: dict[str, bytes]) -> LogIdentity | None:
    """``sys_uuid`` (a board's unique id, where the firmware writes it), else ``sys_name``."""
    def text(key: str) -> str:
        return info.get(key, b"").split(b"\0", 1)[0].decode("utf-8", "replace").strip()

    name, uuid = text("sys_name"), text("sys_uuid")
    if uuid:
        return LogIdentity(f"ulog-{name or 'board'}-uid-{uuid}",
                           f"ULog sys_uuid {uuid}" + (f", sys_name {name}" if name else ""))
    return LogIdentity(f"ulog-{name}", f"ULog sys_name {name}") if name else None


def _moos_identity(prefix: bytes) -> LogIdentity | None:
    found = MOOSDB_POSTING.search(prefix)
    if found is None:
        return None
    community = found.group(1).decode("utf-8", "replace")
    return LogIdentity(f"moos-{community}", f"MOOSDB community {community} (its DB_ postings)")


def _namespace_identity(path: Path, log_format: str, ros_topics: Collection[str],
                        namespace: str | None) -> LogIdentity | None:
    if not ros_topics:
        return None
    try:
        found = resolve(path, ros_topics, _topic_names(path, log_format), namespace)
    except LogError:
        return None
    if not found.namespace:
        return None
    return LogIdentity(f"ros-{found.namespace.lstrip('/')}",
                       f"topics under the ROS namespace {found.namespace}")


def _topic_names(path: Path, log_format: str) -> set[str]:
    """The log's topics from a bag's index, an MCAP's summary or a db3's topics table where
    whole (a millisecond: no type is built, no message counted), else from its inventory."""
    names: set[str] | None = None
    if log_format == "bag":
        names = bag_topics(path)
    elif log_format in ("mcap", "ros2-mcap"):
        names = summary_topics(bag_storages(path))
    elif log_format == "db3":
        names = db3_topics(bag_storages(path))
    return names if names is not None else {topic.name for topic in inventory(path)[0].topics}
