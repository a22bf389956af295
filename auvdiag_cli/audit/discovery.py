"""Finding the logs under the paths an audit is given: files, folders (walked), and glob
patterns. A log is recognised by its content; a file named like a log whose content is not
one is kept (it becomes an error row: most likely a damaged log), anything else is skipped
and listed, as is a copy of another log (`copies`)."""

import glob
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from adapters import detect_format
from adapters.recognise import topic_csv_files
from auvdiag_cli.audit.copies import copies
from auvdiag_errors import LogError, UsageError

LOG_SUFFIXES = {".bag", ".mcap", ".db3", ".tlog", ".bin", ".ulg", ".alog"}
COMPRESSED_ALOG = ".alog.gz"          # pLogger's CompressAlogs
ROS2_METADATA = "metadata.yaml"


@dataclass
class Discovery:
    logs: list[Path] = field(default_factory=list)
    skipped: list[tuple[Path, str]] = field(default_factory=list)
    companions: list[Path] = field(default_factory=list)   # NAME.* beside a log NAME.ext


def _set_companions_apart(found: Discovery) -> None:
    """Files named after a log beside it (its truth, mission plan, reports) are not
    'unrelated': they are counted, not listed one by one."""
    stems: dict[Path, set[str]] = {}
    for log in found.logs:
        stems.setdefault(log.parent.resolve(), set()).add(log.stem)
    def named_after_a_log(path: Path) -> bool:
        beside = stems.get(path.parent.resolve(), set()) - {path.stem}
        return any(path.name.startswith(f"{stem}.") for stem in beside)

    unrelated = []
    for path, reason in found.skipped:
        if named_after_a_log(path):
            found.companions.append(path)
        else:
            unrelated.append((path, reason))
    found.skipped = unrelated
    # A companion can itself read as a log (a truth table is a CSV with a header): NAME.x.csv
    # beside NAME.mcap is the log's, not a dive of its own. A binary log named after another
    # (run.1.bin beside run.bin) is judged by its content (`copies`).
    readable_companions = [log for log in found.logs if log.suffix.lower() == ".csv"
                           and named_after_a_log(log)]
    found.companions += readable_companions
    found.logs = [log for log in found.logs if log not in readable_companions]


def _set_copies_apart(found: Discovery) -> None:
    """A copy of another log found (`copies`) is skipped, with the reason."""
    copied = copies(found.logs)
    found.skipped += list(copied.items())
    found.logs = [log for log in found.logs if log not in copied]


def _expand(pattern: str) -> list[Path]:
    path = Path(pattern)
    if path.exists():
        return [path]
    if glob.has_magic(pattern):
        return sorted(Path(p) for p in glob.glob(pattern, recursive=True))
    return [path]


def _is_log(path: Path) -> bool:
    try:
        detect_format(path)
    except LogError:
        return False
    return True


def _classify(path: Path, found: Discovery) -> None:
    if _is_log(path):
        found.logs.append(path)
    elif path.suffix.lower() in LOG_SUFFIXES or path.name.lower().endswith(COMPRESSED_ALOG):
        found.logs.append(path)          # named like a log: its error row says what is wrong
    else:
        found.skipped.append((path, "not a log this tool reads"))


def _walk(folder: Path, found: Discovery, exclude: set[Path]) -> None:
    if (folder / ROS2_METADATA).is_file():
        found.logs.append(folder)        # a ROS 2 bag: one log, its files are not walked
        return
    # A folder of per-topic CSVs is one log; other files beside them are logs of their own
    # (the bag they were exported from, over the same time, is then a copy: `copies`).
    topics = set(topic_csv_files(folder))
    if topics:
        found.logs.append(folder)
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith(".") or entry.resolve() in exclude or entry in topics:
            continue
        if entry.is_dir():
            _walk(entry, found, exclude)
        elif entry.is_file():
            _classify(entry, found)


def discover(paths: Sequence[str], exclude: Sequence[Path] = ()) -> Discovery:
    """Logs in the order found (each once), and what was skipped and why."""
    found = Discovery()
    excluded = {p.resolve() for p in exclude}
    for pattern in paths:
        for path in _expand(pattern):
            if not path.exists():
                found.skipped.append((path, "no such file or directory"))
            elif path.is_dir():
                _walk(path, found, excluded)
            else:
                _classify(path, found)
    unique: dict[Path, Path] = {}
    for log in found.logs:
        unique.setdefault(log.resolve(), log)
    found.logs = list(unique.values())
    _set_companions_apart(found)
    _set_copies_apart(found)
    return found


def expand_logs(paths: Sequence[Path], progress: Callable[[str], None]) -> list[Path]:
    """The logs given, a folder standing for every log under it (a ROS 2 bag folder is
    one log); what a folder holds that is not a log is reported through ``progress``."""
    expanded: list[Path] = []
    for path in paths:
        if not path.is_dir() or (path / ROS2_METADATA).is_file() or topic_csv_files(path):
            expanded.append(path)
            continue
        found = discover([str(path)])
        for skipped, why in found.skipped:
            progress(f"left out {skipped}: {why}")
        if not found.logs:
            raise UsageError(f"{path}: the folder holds no log this tool reads")
        expanded += found.logs
    return expanded
