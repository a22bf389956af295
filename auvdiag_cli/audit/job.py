"""An audit from start to end: find the logs, reuse what an earlier run finished, diagnose
the rest, and keep the table and the fleet PDF in step with what is done."""

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from auvdiag_cli.audit.discovery import discover
from auvdiag_cli.audit.fleet_vehicle import VehicleRule
from auvdiag_cli.audit.progress import Reporter
from auvdiag_cli.audit.record import AuditRecord
from auvdiag_cli.audit.runner import run_tasks
from auvdiag_cli.audit.store import Inputs, ResultStore, folder_digest, text_digest
from auvdiag_cli.audit.table import build_table, write_tables
from auvdiag_cli.audit.worker import AuditTask
from auvdiag_cli.digest import log_digest
from auvdiag_cli.vehicle.profile import load_profile
from models.store import default_model_dir, load_model

TABLE_EVERY_S = 5.0      # rewrite the table at most this often while logs finish


@dataclass
class AuditOptions:
    paths: Sequence[str]
    output: Path
    profile: Path | None = None
    model: Path | None = None
    jobs: int = 1
    scheduler: str | None = None
    mcap: bool = False           # each diagnosis also as an MCAP beside its JSON
    vehicle_from: str = "log"    # which vehicle of the fleet a log is: `VehicleRule`


@dataclass
class AuditResult:
    records: list[AuditRecord] = field(default_factory=list)
    skipped: list[tuple[Path, str]] = field(default_factory=list)
    companions: int = 0
    reused: int = 0
    computed: int = 0
    interrupted: bool = False

    def count(self, verdict: str) -> int:
        return sum(1 for r in self.records if r.analysed and r.verdict == verdict)

    def summary(self, output: Path) -> str:
        """The line an audit ends with: what it found and where the results are."""
        partly = f" ({self.partly_judged} judged in part)" if self.partly_judged else ""
        return (f"{len(self.records)} logs: {self.count('normal')} normal{partly}, "
                f"{self.count('fault')} fault, {self.count('undetermined')} undetermined, "
                f"{self.errors} not analysable, {self.damaged} partial (damaged); "
                f"{len(self.skipped)} files skipped; "
                f"{self.computed} diagnosed now, {self.reused} reused; results in {output}")

    @property
    def errors(self) -> int:
        return sum(1 for r in self.records if r.error)

    @property
    def partly_judged(self) -> int:
        """NORMAL verdicts over less than every signal and actuator of the profile, or judged
        only from partway into the log."""
        return sum(1 for r in self.records if r.partly_judged)

    @property
    def damaged(self) -> int:
        """Logs analysed only up to damage (salvaged), not counting errors."""
        return sum(1 for r in self.records if r.damaged)


def _inputs(options: AuditOptions) -> tuple[Inputs, str, VehicleRule]:
    """Validate the profile and the model once (a bad one fails the audit before it
    starts) and fingerprint them; returns the model directory the workers load, and how
    a log's vehicle is found."""
    profile = load_profile(options.profile)
    model_dir = options.model or default_model_dir(profile.name)
    load_model(options.model, profile.name)
    rule = VehicleRule.parse(options.vehicle_from, profile.sources.get("ros"))
    return (Inputs(folder_digest(model_dir), text_digest(repr(profile))), str(model_dir),
            rule)


class TableWriter:
    """Rewrites the table as results arrive, no more often than every few seconds."""

    def __init__(self, output: Path) -> None:
        self.output, self.last = output, 0.0

    def write(self, records: Sequence[AuditRecord], force: bool = False) -> None:
        if force or (records and time.monotonic() - self.last >= TABLE_EVERY_S):
            write_tables(build_table(records), self.output)
            self.last = time.monotonic()


def run_audit(options: AuditOptions, reporter: Reporter) -> AuditResult:
    inputs, model_dir, rule = _inputs(options)
    options.output.mkdir(parents=True, exist_ok=True)
    found = discover(options.paths, exclude=[options.output])
    store = ResultStore(options.output, inputs, options.mcap)
    result = AuditResult(skipped=found.skipped, companions=len(found.companions))
    done: dict[str, AuditRecord] = {}
    digests: dict[str, str] = {}
    vehicles = {str(log): rule.vehicle_of(log) for log in found.logs}
    tasks = []
    for log in found.logs:
        try:
            digests[str(log)] = log_digest(log)
        except OSError as error:
            done[str(log)] = AuditRecord(str(log), f"{log}: unreadable: {error.strerror}",
                                         fleet_vehicle=vehicles[str(log)].vehicle)
            continue
        reused = store.reusable(log, digests[str(log)])
        try:
            if reused is not None:
                done[str(log)] = AuditRecord.from_report(
                    store.with_vehicle(log, reused, vehicles[str(log)]))
        except ValueError:         # a stored result this release cannot read: done again
            reused = None
        if reused is None:
            profile = None if options.profile is None else str(options.profile)
            tasks.append(AuditTask(str(log), profile, model_dir))
    result.reused = len(done)
    table = TableWriter(options.output)
    reporter.start(len(found.logs), result.reused)
    try:
        for outcome in run_tasks(tasks, options.jobs, options.scheduler):
            done[outcome.log] = AuditRecord.from_report(
                store.save(outcome, digests[outcome.log], vehicles[outcome.log]))
            result.computed += 1
            reporter.done(done[outcome.log])
            table.write(list(done.values()))
    except KeyboardInterrupt:
        result.interrupted = True
    finally:
        reporter.stop()
        result.records = list(done.values())
        table.write(result.records, force=True)
    return result
