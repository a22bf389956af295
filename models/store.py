"""Model directories: ``weights.pt`` (a plain state dict, loaded with ``weights_only=True`` so
no code runs) and ``model.json`` (readable, versioned metadata)."""

import hashlib
import json
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any

import torch

from models.dynamics import Normaliser, RecurrentDynamics
from models.fast import FastDynamics

FORMAT_NAME = "auvdiag-model"
FORMAT_VERSION = 1
WEIGHTS_FILE, METADATA_FILE = "weights.pt", "model.json"


class ModelFileError(Exception):
    """A model directory cannot be used; the message names the path and the problem."""


@dataclass
class LoadedModel:
    network: RecurrentDynamics
    normaliser: Normaliser
    metadata: dict[str, Any]
    path: str

    @property
    def identity(self) -> dict[str, Any]:
        """What a report needs to say which model judged the log."""
        meta = self.metadata
        return {"name": meta.get("name"), "vehicle": meta.get("vehicle"), "path": self.path,
                "weights_sha256": meta.get("weights_sha256"), "created": meta.get("created"),
                "heldout_error_rms": meta.get("heldout_error", {}).get("rms"),
                "thresholds_calibrated": "calibration" in meta}

    @cached_property
    def fast(self) -> FastDynamics:
        """The NumPy replay path of the same network (the diagnosis hot path)."""
        return FastDynamics.from_module(self.network)

    @property
    def command_names(self) -> tuple[str, ...]:
        return tuple(self.metadata["signals"]["commands"])

    @property
    def sensor_names(self) -> tuple[str, ...]:
        return tuple(s["name"] for s in self.metadata["signals"]["sensors"])


def default_model_dir(vehicle: str = "twin-burger") -> Path:
    """Where the shipped model of a vehicle (the profile's ``vehicle.name``) lives."""
    return Path(str(resources.files("models") / vehicle.replace("-", "_")))


def save_model(directory: Path, network: RecurrentDynamics, normaliser: Normaliser,
               metadata: dict[str, Any]) -> None:
    """Write weights and metadata; the metadata gains the architecture and weight digest."""
    directory.mkdir(parents=True, exist_ok=True)
    weights = directory / WEIGHTS_FILE
    torch.save({k: v.detach().clone() for k, v in network.state_dict().items()}, weights)
    full = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        **metadata,
        "architecture": {"type": "gru-residual", "hidden": network.hidden,
                         "n_commands": network.n_commands, "n_states": network.n_states},
        "normalisation": {"command_scale": list(normaliser.command_scale),
                          "state_scale": list(normaliser.state_scale),
                          "delta_ratio": normaliser.delta_ratio},
        "weights_sha256": hashlib.sha256(weights.read_bytes()).hexdigest(),
    }
    (directory / METADATA_FILE).write_text(json.dumps(full, indent=2) + "\n", encoding="utf-8")


def load_model(directory: Path | None = None, vehicle: str = "twin-burger") -> LoadedModel:
    """Load a model directory, or when ``directory`` is None the model shipped for
    ``vehicle`` (a profile's ``vehicle.name``)."""
    label = f"builtin:{vehicle.replace('-', '_')}" if directory is None else str(directory)
    if directory is None:
        directory = default_model_dir(vehicle)
        if not (directory / METADATA_FILE).is_file():
            raise ModelFileError(f"no model is shipped for vehicle {vehicle!r}: train one "
                                 "with 'auvdiag train' and pass it with --model")
    meta_path, weights_path = directory / METADATA_FILE, directory / WEIGHTS_FILE
    if not meta_path.is_file() or not weights_path.is_file():
        raise ModelFileError(f"{directory}: not a model directory "
                             f"(needs {METADATA_FILE} and {WEIGHTS_FILE})")
    try:
        metadata = json.loads(meta_path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        raise ModelFileError(f"{meta_path}: unreadable metadata: {error}") from None
    if metadata.get("format") != FORMAT_NAME:
        raise ModelFileError(f"{meta_path}: not an auvdiag model file")
    if metadata.get("format_version") != FORMAT_VERSION:
        raise ModelFileError(f"{meta_path}: model format version {metadata.get('format_version')}"
                             f" is not supported (this tool reads version {FORMAT_VERSION})")
    try:
        arch, norm = metadata["architecture"], metadata["normalisation"]
        network = RecurrentDynamics(arch["n_commands"], arch["n_states"], arch["hidden"],
                                    norm["delta_ratio"])
        state = torch.load(weights_path, map_location="cpu", weights_only=True)
        network.load_state_dict(state)
        normaliser = Normaliser(tuple(norm["command_scale"]), tuple(norm["state_scale"]),
                                norm["delta_ratio"])
    except Exception as error:  # torch raises many types (pickle refusals, zip, shape)
        raise ModelFileError(f"{directory}: model does not load: {error}") from None
    network.eval()
    return LoadedModel(network, normaliser, metadata, label)
