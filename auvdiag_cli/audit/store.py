"""The audit's per-log results on disk: one JSON report (and its time histories) per log,
each written atomically the moment it is known. A result is reused by a later run only if
the log's bytes, the model and the profile are the ones it was computed from."""

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from auvdiag_cli import __version__
from auvdiag_cli.audit.fleet_vehicle import FleetVehicle
from auvdiag_cli.audit.worker import AuditOutcome
from auvdiag_cli.digest import log_digest
from auvdiag_cli.files import write_json
from auvdiag_cli.reports.mcap_export import write_diagnosis_mcap
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.series import save_series, series_path

RESULTS_FOLDER = "logs"


def folder_digest(folder: Path) -> str:
    """SHA-256 over the names and bytes of a model directory's files."""
    return log_digest(folder)


def text_digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class Inputs:
    """What a result depends on besides the log itself."""

    model_sha256: str
    profile_sha256: str

    def stamp(self, log_sha256: str) -> dict[str, str]:
        return {"log_sha256": log_sha256, "model_sha256": self.model_sha256,
                "profile_sha256": self.profile_sha256, "tool": f"auvdiag {__version__}"}


class ResultStore:
    def __init__(self, output: Path, inputs: Inputs, mcap: bool = False) -> None:
        self.folder = output / RESULTS_FOLDER
        self.folder.mkdir(parents=True, exist_ok=True)
        self.inputs = inputs
        self.mcap = mcap     # also write each diagnosis as an MCAP beside its JSON

    def path_for(self, log: Path) -> Path:
        """A readable, collision-free name: the log's name and a hash of its full path."""
        tag = hashlib.sha1(str(log.resolve()).encode()).hexdigest()[:8]
        return self.folder / f"{log.name}-{tag}.json"

    def reusable(self, log: Path, log_sha256: str) -> dict[str, Any] | None:
        """The stored result for ``log`` if it was computed from these exact inputs."""
        path = self.path_for(log)
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        stamp = record.get("audit", {})
        wanted = self.inputs.stamp(log_sha256)
        if any(stamp.get(key) != wanted[key] for key in ("log_sha256", "model_sha256",
                                                         "profile_sha256")):
            return None
        if self.mcap and not record.get("error") and not path.with_suffix(".mcap").is_file():
            return None
        return record

    def with_vehicle(self, log: Path, record: dict[str, Any], vehicle: FleetVehicle
                     ) -> dict[str, Any]:
        """A reused record with the fleet vehicle this run assigns (rewritten if it moved)."""
        entry = {"id": vehicle.vehicle, "from": vehicle.source}
        if record.get("audit", {}).get("vehicle") != entry:
            record = {**record, "audit": {**record.get("audit", {}), "vehicle": entry}}
            write_json(record, self.path_for(log))
        return record

    def save(self, outcome: AuditOutcome, log_sha256: str, vehicle: FleetVehicle
             ) -> dict[str, Any]:
        """Write the outcome (series first, so a JSON on disk always has its series)."""
        path = self.path_for(Path(outcome.log))
        record: dict[str, Any] = dict(outcome.document or {"log": outcome.log})
        record["error"] = outcome.error
        if outcome.series:
            sidecar = series_path(path)
            save_series(outcome.series, sidecar)
            record["series_file"] = sidecar.name
            if self.mcap and outcome.document is not None and outcome.final:
                write_diagnosis_mcap(Report.from_json(outcome.document), outcome.series,
                                     path.with_suffix(".mcap"))
        record["audit"] = {**self.inputs.stamp(log_sha256), "seconds": outcome.seconds,
                           "peak_rss_mb": outcome.peak_rss_mb, "result_file": path.name,
                           "vehicle": {"id": vehicle.vehicle, "from": vehicle.source}}
        if outcome.final:
            write_json(record, path)
        return record
