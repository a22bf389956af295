"""Valid logs for the fuzzer to damage: one short simulated dive written in every format the
tool reads, by the same writers (rosbags, mcap, the MAVLink and DataFlash writers) as the
test suite uses, plus any real logs a user adds."""

import copy
import shutil
from dataclasses import dataclass
from pathlib import Path

from adapters import detect_format
from auvdiag_cli.simulator.run import SimulatedDive, Stream, simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import LOG_FORMATS, write_log
from auvdiag_cli.vehicle.profile import Profile

SEED_SCENARIO = "routine-flow-sensor-dead"   # markers, DMS segments and a fault: many paths
SEED_SECONDS = 40.0


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


def _storage(path: Path) -> Path:
    """The file that is damaged: a ROS 2 bag's storage, a per-topic CSV folder's largest
    topic."""
    if path.is_dir():
        files = sorted(path.iterdir())
        storage = [p for p in files if p.suffix in (".db3", ".mcap")]
        return storage[0] if storage else max(files, key=lambda p: p.stat().st_size)
    return path


def simulated_seeds(folder: Path, profile: Profile, formats: tuple[str, ...] = LOG_FORMATS
                    ) -> list[SeedLog]:
    """One seed per format, written under ``folder``."""
    dive = _cropped(simulate(get_scenario(SEED_SCENARIO, profile), profile, 7), SEED_SECONDS)
    seeds = []
    for fmt in formats:
        path = folder / (f"seed.{fmt}" if fmt in ("bag", "mcap", "tlog", "bin")
                         else f"seed-{fmt}")
        write_log(dive, profile, path, fmt)
        seeds.append(SeedLog(fmt, path, _storage(path)))
    return seeds


def real_seed(path: Path) -> SeedLog:
    """A log from the field as a seed (its format is checked now)."""
    detect_format(path)
    return SeedLog(path.name, path, _storage(path))
