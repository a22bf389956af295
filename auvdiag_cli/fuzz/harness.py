"""Run damaged logs through `inspect`, `init-profile` and `diagnose`, each case in a child
process with a time limit and an address-space limit, and sort what happens into outcomes.

An outcome is *read* (analysed, perhaps with notes), *rejected* (a one-line `AuvdiagError`
that names the file), or a defect: *crash* (any other exception, a signal, or an error
message that is not one line naming the file), *hang* (over the time limit), *memory* (the
address-space limit reached), *output* (library code printed to the terminal). Children
are forked from a warmed-up parent, so a case costs the work on the log, not an interpreter
start (Linux and macOS; needs ``os.fork``)."""

import json
import os
import resource
import select
import signal
import tempfile
import time
import traceback
from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from auvdiag_cli.fuzz.mutations import mutate
from auvdiag_cli.fuzz.seeds import SeedLog
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

DEFECTS = ("crash", "hang", "memory", "output")
_DETAIL_CHARS = 1500


@dataclass(frozen=True)
class Case:
    seed_log: SeedLog
    number: int                      # with the seed log's name, reproduces the case

    @property
    def seed(self) -> int:
        return hash_seed(self.seed_log.name, self.number)


def hash_seed(name: str, number: int) -> int:
    """A stable seed from a name and a number (Python's hash() is salted per process)."""
    import zlib

    return zlib.crc32(name.encode()) * 1_000_003 + number


@dataclass
class CaseResult:
    log: str
    number: int
    mutations: list[str]
    outcome: str
    seconds: float
    peak_rss_mb: float
    detail: str = ""


@dataclass
class Limits:
    time_s: float = 20.0
    memory_mb: int = 1024            # address space a case may add to the forked parent's


def exercise(path: Path, profile: Profile, model: LoadedModel) -> tuple[str, str]:
    """What `auvdiag inspect`, `auvdiag init-profile` and `auvdiag diagnose --json -` do
    with ``path``, without the terminal: (outcome, detail). Raises nothing the CLI would not
    turn into one line."""
    from auvdiag_cli.engine.diagnosis import diagnose
    from auvdiag_cli.jobs.inspect import inspect_log
    from auvdiag_cli.jobs.profile_draft import draft_profile
    from auvdiag_cli.reports.report_build import build_report
    from auvdiag_cli.reports.series import series_from_diagnosis
    from auvdiag_cli.reports.text import inspection_lines, summary_lines
    from auvdiag_errors import AuvdiagError

    outcomes, details = [], []
    for command in ("inspect", "init-profile", "diagnose"):
        try:
            if command == "inspect":
                inspection_lines(inspect_log(path, profile))
            elif command == "init-profile":
                draft_profile(path, "fuzzed")
            else:
                result = diagnose(path, profile, model)
                report = build_report(result)
                json.dumps(report.to_json())
                series_from_diagnosis(result)
                summary_lines(report)
            outcomes.append("read")
        except AuvdiagError as error:
            message = str(error)
            if "\n" in message or str(path) not in message:
                outcomes.append("crash")
                details.append(f"{command}: error message is not one line naming the file: "
                               f"{message!r}")
            else:
                outcomes.append("rejected")
                details.append(f"{command}: {message}")
    # The case is what `diagnose` made of the log, unless `inspect` failed worse.
    return ("crash" if "crash" in outcomes else outcomes[-1]), "; ".join(details)


def _virtual_bytes() -> int:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


Check = Callable[[Path, Profile, LoadedModel], tuple[str, str]]


def _child(case_path: Path, profile: Profile, model: LoadedModel, limits: Limits,
           write_fd: int, check: Check) -> None:
    """Runs in the forked child; reports on ``write_fd`` and never returns."""
    code = 0
    try:
        if os.path.exists("/proc/self/statm"):
            ceiling = _virtual_bytes() + limits.memory_mb * (1 << 20)
            resource.setrlimit(resource.RLIMIT_AS, (ceiling, ceiling))
        # Library code must not print: what reaches the terminal would break the one-line
        # error (and `--json -` on stdout). Anything written is caught and reported.
        printed = tempfile.TemporaryFile()  # noqa: SIM115 (lives until os._exit)
        os.dup2(printed.fileno(), 1)
        os.dup2(printed.fileno(), 2)
        try:
            outcome, detail = check(case_path, profile, model)
            printed.seek(0)
            stray = printed.read(300)
            if stray:
                outcome, detail = "output", f"printed {stray!r}; {detail}"
        except MemoryError:
            outcome, detail = "memory", "MemoryError: the address-space limit was reached"
        except BaseException as error:
            outcome = "crash"
            frames = traceback.extract_tb(error.__traceback__)[-3:]
            where = " <- ".join(f"{Path(f.filename).name}:{f.lineno}" for f in reversed(frames))
            detail = f"{type(error).__name__}: {error} at {where}"
        os.write(write_fd, json.dumps({"outcome": outcome,
                                       "detail": detail[:_DETAIL_CHARS]}).encode())
    except BaseException:
        code = 3
    finally:
        os._exit(code)


@dataclass
class _Running:
    case: Case
    mutations: list[str]
    folder: Path
    read_fd: int
    started: float
    chunks: list[bytes] = field(default_factory=list)


def _start(case: Case, profile: Profile, model: LoadedModel, limits: Limits, workdir: Path,
           check: Check) -> tuple[int, _Running]:
    folder = Path(tempfile.mkdtemp(prefix="case-", dir=workdir))
    log_path, storage = case.seed_log.copy_to(folder)
    damaged, mutations = mutate(storage.read_bytes(), case.seed)
    storage.write_bytes(damaged)
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_fd)
        _child(log_path, profile, model, limits, write_fd, check)
    os.close(write_fd)
    return pid, _Running(case, mutations, folder, read_fd, time.perf_counter())


def _finish(running: _Running, status: int, usage: Any, timed_out: bool) -> CaseResult:
    import shutil

    while chunk := os.read(running.read_fd, 65536):
        running.chunks.append(chunk)
    os.close(running.read_fd)
    shutil.rmtree(running.folder, ignore_errors=True)
    peak_mb = usage.ru_maxrss / 1024 if usage is not None else 0.0
    result = CaseResult(running.case.seed_log.name, running.case.number, running.mutations,
                        "crash", round(time.perf_counter() - running.started, 3),
                        round(peak_mb, 1))
    if timed_out:
        result.outcome, result.detail = "hang", "over the time limit"
    elif running.chunks:
        reported = json.loads(b"".join(running.chunks))
        result.outcome, result.detail = reported["outcome"], reported["detail"]
    elif os.WIFSIGNALED(status):
        result.detail = f"killed by signal {os.WTERMSIG(status)}"
    else:
        result.detail = f"exited with status {os.waitstatus_to_exitcode(status)} and no report"
    return result


def run_cases(cases: Iterable[Case], profile: Profile, model: LoadedModel, limits: Limits,
              jobs: int, check: Check = exercise) -> Iterator[CaseResult]:
    """Each case in its own forked child, ``jobs`` at a time; results as they finish.
    ``check`` is what a child does with its damaged log (the CLI's path by default)."""
    pending = iter(cases)
    running: dict[int, _Running] = {}
    with tempfile.TemporaryDirectory(prefix="auvdiag-fuzz-") as workdir:
        exhausted = False
        while running or not exhausted:
            while not exhausted and len(running) < jobs:
                case = next(pending, None)
                if case is None:
                    exhausted = True
                    break
                pid, started = _start(case, profile, model, limits, Path(workdir), check)
                running[pid] = started
            if not running:
                break
            _drain_pipes(running)
            pid, status, usage = os.wait4(-1, os.WNOHANG)
            if pid in running:
                yield _finish(running.pop(pid), status, usage, False)
                continue
            now = time.perf_counter()
            for late_pid in [p for p, r in running.items() if now - r.started > limits.time_s]:
                os.kill(late_pid, signal.SIGKILL)
                _, status, usage = os.wait4(late_pid, 0)
                yield _finish(running.pop(late_pid), status, usage, True)


def _drain_pipes(running: dict[int, _Running]) -> None:
    """Wait briefly for a child to report, emptying pipes so no child blocks writing."""
    by_fd = {r.read_fd: r for r in running.values()}
    ready, _, _ = select.select(list(by_fd), [], [], 0.005)
    for fd in ready:
        chunk = os.read(fd, 65536)
        if chunk:
            by_fd[fd].chunks.append(chunk)


def summarise(results: list[CaseResult]) -> dict[str, Any]:
    """Counts per outcome, the slowest case and the peak memory, for one seed log."""
    counts = {name: sum(1 for r in results if r.outcome == name)
              for name in ("read", "rejected", *DEFECTS)}
    slowest = max(results, key=lambda r: r.seconds, default=None)
    return {"cases": len(results), **counts,
            "defects": sum(counts[name] for name in DEFECTS),
            "slowest_s": slowest.seconds if slowest else None,
            "slowest_case": slowest.number if slowest else None,
            "peak_rss_mb": max((r.peak_rss_mb for r in results), default=None),
            "defect_cases": [asdict(r) for r in results if r.outcome in DEFECTS]}
