"""Valid logs for the fuzzer to damage: one short simulated dive written in every format the
tool reads, by the same writers (rosbags, mcap, the MAVLink and DataFlash writers) as the
test suite uses, plus any real logs a user adds. Each ROS format is written a second time
with the vehicle's software talking beside the dive (`/rosout`, mavros status texts,
`/diagnostics`: "bag+words"), so that damage lands in what those readers decode too; the
plain seeds stay as they were, and the cases found on them replay as they did."""

import copy
import gzip
import shutil
from dataclasses import dataclass
from pathlib import Path

from adapters import detect_format
from auvdiag_cli.simulator.run import SimulatedDive, Stream, simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import LOG_FORMATS, ROS1_FORMATS, ExtraTopic, write_log
from auvdiag_cli.simulator.writers.ros import hardware_status, node_log, status_texts
from auvdiag_cli.vehicle.profile import Profile

SEED_SCENARIO = "routine-flow-sensor-dead"   # markers, DMS segments and a fault: many paths
SEED_SECONDS = 40.0
WITH_WORDS = "+words"
ROS_SEED_FORMATS = ("bag", "db3", "ros2-mcap", "mcap", "topic-csv")
# Text logs read gzip-compressed as well (`adapters.compressed`): damage lands in the stream.
COMPRESSED = ".gz"
COMPRESSED_SEED_FORMATS = ("alog", "csv")
SEED_FORMATS = (*LOG_FORMATS, *(fmt + WITH_WORDS for fmt in ROS_SEED_FORMATS),
                *(fmt + COMPRESSED for fmt in COMPRESSED_SEED_FORMATS))
WORDS_TOPIC = "/rosout"      # a per-topic CSV folder's file that is damaged: the nodes' words


@dataclass(frozen=True)
class SeedLog:
    """A valid log and the file inside it that the fuzzer damages."""

    name: str            # the format, or the real log's file name
    path: Path           # what `diagnose` is given (a ROS 2 bag: its directory)
    storage: Path        # the bytes that are mutated

    def copy_to(self, folder: Path) -> tuple[Path, Path]:
        """A fresh copy of the log in ``folder``: (log path, storage path)."""
        target = folder / self.path.name
        if self.path.is_dir():
            shutil.copytree(self.path, target)
        else:
            shutil.copyfile(self.path, target)
        return target, target / self.storage.relative_to(self.path) if self.path.is_dir() \
            else target


def _cropped(dive: SimulatedDive, seconds: float) -> SimulatedDive:
    """The first ``seconds`` of a dive (short seeds make fast cases)."""
    def crop(stream: Stream) -> Stream:
        kept = [i for i, t in enumerate(stream.times_s) if t <= seconds]
        return Stream([stream.times_s[i] for i in kept], [stream.values[i] for i in kept])

    short = copy.copy(dive)
    short.commands = crop(dive.commands)
    short.sensors = {name: crop(stream) for name, stream in dive.sensors.items()}
    short.markers = [(t, label) for t, label in dive.markers if t <= seconds]
    short.truth = dive.truth[dive.truth["t_s"] <= seconds]
    return short


def _storage(path: Path, topic: str | None = None) -> Path:
    """The file that is damaged: a ROS 2 bag's storage, a per-topic CSV folder's file of
    ``topic`` (None: its largest)."""
    if path.is_dir():
        files = sorted(path.iterdir())
        storage = [p for p in files if p.suffix in (".db3", ".mcap")]
        named = [p for p in files if topic is not None
                 and p.stem.endswith(topic.replace("/", "-"))]
        return (storage or named or [max(files, key=lambda p: p.stat().st_size)])[0]
    return path


def software_words(start_ns: int, seconds: float, ros1: bool) -> list[ExtraTopic]:
    """What a vehicle's software says over ``seconds`` from ``start_ns``: its nodes at every
    level twice a second, the autopilot's texts at every severity, and three hardware
    statuses once a second, one wrong from the start, one worsening, one recovering."""
    def at(step_s: float) -> list[int]:
        return [start_ns + int(k * step_s * 1e9) for k in range(int(seconds / step_s))]

    levels, nodes = (1, 2, 4, 8, 16), ("/dvl_driver", "/thruster_driver", "/mission")
    texts = ("DVL lost bottom lock", "thruster 2 not responding", "waypoint 3 reached")
    statuses = [(time_ns, [(2, "battery", "low voltage"), (min(3, k // 10), "sonar", "link"),
                           (max(0, 2 - k // 10), "leak", "sensor")])
                for k, time_ns in enumerate(at(1.0))]
    return [node_log("/rosout", ros1, [(time_ns, levels[k % 5], nodes[k % 3], texts[k % 3])
                                       for k, time_ns in enumerate(at(0.5))]),
            status_texts("/mavros/statustext/recv", ros1,
                         [(time_ns, k % 8, f"PreArm: check {k}")
                          for k, time_ns in enumerate(at(2.0))]),
            hardware_status("/diagnostics", ros1, statuses)]


def simulated_seeds(folder: Path, profile: Profile, formats: tuple[str, ...] = SEED_FORMATS
                    ) -> list[SeedLog]:
    """One seed per format (a ROS format's name + ``WITH_WORDS``: with `software_words`),
    written under ``folder``."""
    dive = _cropped(simulate(get_scenario(SEED_SCENARIO, profile), profile, 7), SEED_SECONDS)
    seeds = []
    for name in formats:
        fmt, words = name.removesuffix(WITH_WORDS), name.endswith(WITH_WORDS)
        if words and fmt not in ROS_SEED_FORMATS:
            raise ValueError(f"{name}: only a ROS format carries words")
        if fmt.endswith(COMPRESSED):
            seeds.append(_compressed_seed(folder, dive, profile, fmt.removesuffix(COMPRESSED)))
            continue
        tag = "-words" if words else ""
        path = folder / (f"seed{tag}.{fmt}" if fmt in ("bag", "mcap", "tlog", "bin")
                         else f"seed-{fmt}{tag}")
        extra = software_words(dive.start_ns, SEED_SECONDS, fmt in ROS1_FORMATS) \
            if words else []
        write_log(dive, profile, path, fmt, extra)
        seeds.append(SeedLog(name, path, _storage(path, WORDS_TOPIC if words else None)))
    return seeds


def _compressed_seed(folder: Path, dive: SimulatedDive, profile: Profile, fmt: str) -> SeedLog:
    if fmt not in COMPRESSED_SEED_FORMATS:
        raise ValueError(f"{fmt}{COMPRESSED}: only a text log is read compressed")
    plain = folder / f"seed-{fmt}-plain"
    write_log(dive, profile, plain, fmt)
    path = folder / f"seed-{fmt}{COMPRESSED}"
    path.write_bytes(gzip.compress(plain.read_bytes(), mtime=0))
    plain.unlink()
    return SeedLog(f"{fmt}{COMPRESSED}", path, path)


def real_seed(path: Path) -> SeedLog:
    """A log from the field as a seed (its format is checked now)."""
    detect_format(path)
    return SeedLog(path.name, path, _storage(path))
