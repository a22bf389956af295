"""Model directories: ``weights.npz`` (the network's state dict as plain arrays, loaded with
``allow_pickle=False`` so no code runs; beside it, where training kept them, ``linear``, the
least-squares linear model, ``linear_replay``, the same refined against the replay's error,
and ``on_linear/…``, the network trained on top of the least-squares one) and
``model.json`` (readable, versioned metadata; ``predictors`` says which predictor each
signal is read from).
Diagnosis runs on the NumPy path and never imports torch; the torch module is built only
when asked for (training, comparisons). Version 1 directories (``weights.pt``, a torch state
dict read with ``weights_only=True``) still load."""

import hashlib
import json
import os
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from auvdiag_errors import ModelError
from models.card import ModelCard, ModelIdentity
from models.effort_model import EffortModel
from models.fast import (
    LINEAR_REPLAY,
    NETWORK,
    PREDICTOR_KINDS,
    ChosenDynamics,
    FastDynamics,
    linear_only,
)
from models.normaliser import Normaliser
from models.relation_forms import Relations, relations_from_json

if TYPE_CHECKING:
    from models.dynamics import RecurrentDynamics

FORMAT_NAME = "auvdiag-model"
FORMAT_VERSION = 2
WEIGHTS_FILE, METADATA_FILE = "weights.npz", "model.json"
LINEAR_KEY, LINEAR_REPLAY_KEY, ON_LINEAR_PREFIX = "linear", "linear_replay", "on_linear/"
LEGACY_WEIGHTS_FILE = "weights.pt"          # format version 1


class ModelFileError(ModelError):
    """A model directory cannot be used; the message names the path and the problem."""


@dataclass
class LoadedModel:
    state: dict[str, np.ndarray]     # the network's state dict, as arrays
    normaliser: Normaliser
    # model.json, typed; only the writers (train, calibrate, relate, score) change it, with
    # `update_entries`.
    card: ModelCard
    path: str
    extra: dict[str, np.ndarray] = field(default_factory=dict)   # linear, on_linear/…
    directory: Path | None = None    # where it was read from

    @property
    def shipped(self) -> bool:
        """The model shipped with the tool for a vehicle (not one read from a directory
        given by the user)."""
        return self.path.startswith("builtin:")

    @property
    def unsaved(self) -> bool:
        """model.json in its directory no longer holds what this model does (changed in
        memory by calibrate, relate or score, and not saved); False without a directory."""
        if self.directory is None:
            return False
        saved = json.loads((self.directory / METADATA_FILE).read_text("utf-8"))
        return bool(saved != self.card.to_document())

    def update_entries(self, **entries: object) -> None:
        """Replace model.json entries (not yet written), each a typed value or plain JSON:
        the replay (which predictor each signal is read from), relations and effort are
        read afresh from the new card."""
        self.card = self.card.with_entries(**entries)
        for parsed in ("dynamics", "relations", "effort"):
            self.__dict__.pop(parsed, None)

    def with_entries(self, **entries: object) -> "LoadedModel":
        """The same model with these model.json entries replaced; this one is unchanged."""
        return replace(self, card=self.card.with_entries(**entries))

    @cached_property
    def network(self) -> "RecurrentDynamics":
        """The torch module (imports torch; diagnosis does not need it)."""
        import torch

        from models.dynamics import RecurrentDynamics

        card = self.card
        network = RecurrentDynamics(card.drive_width, len(card.sensor_names), card.hidden,
                                    self.normaliser.delta_ratio)
        network.load_state_dict({k: torch.from_numpy(v) for k, v in self.state.items()})
        network.eval()
        return network

    @cached_property
    def fast(self) -> FastDynamics:
        """The NumPy replay path of the same network (the diagnosis hot path)."""
        return FastDynamics.from_state(self.state, self.card.drive_width,
                                       self.normaliser.delta_ratio)

    @property
    def predictors(self) -> dict[str, str]:
        """Which predictor each signal is read from (the network alone for a model trained
        before the choice was made)."""
        return dict(self.card.predictors)

    @cached_property
    def dynamics(self) -> ChosenDynamics:
        """The replay: each signal from its chosen predictor (the diagnosis hot path)."""
        kinds = list(self.predictors.values())
        order = list(dict.fromkeys(kinds))
        return ChosenDynamics(tuple(self._member(kind) for kind in order),
                              tuple(order.index(kind) for kind in kinds))

    def _member(self, kind: str) -> FastDynamics:
        if kind not in PREDICTOR_KINDS:
            raise ValueError(f"unknown predictor {kind!r}")
        if kind == NETWORK:
            return self.fast
        n_commands = self.card.drive_width
        key = LINEAR_REPLAY_KEY if kind == LINEAR_REPLAY else LINEAR_KEY
        if key not in self.extra:
            raise ValueError(f"model.json reads signals from the {kind} predictor, but "
                             f"{WEIGHTS_FILE} holds no {key} weights")
        linear = self.extra[key]
        if kind in ("linear", LINEAR_REPLAY):
            return linear_only(linear, n_commands)
        state = {k[len(ON_LINEAR_PREFIX):]: v for k, v in self.extra.items()
                 if k.startswith(ON_LINEAR_PREFIX)}
        return FastDynamics.from_state(state, n_commands, self.normaliser.delta_ratio, linear)

    @property
    def identity(self) -> ModelIdentity:
        """What a report needs to say which model judged the log."""
        return self.card.identity(self.path)

    @property
    def horizon_steps(self) -> int | None:
        """How many steps the model predicts before the replay re-starts from the measured
        state; None: the paper's free run (also every model from before horizons)."""
        horizon = self.card.horizon_s
        return None if horizon is None else max(1, round(horizon / self.card.dt_s))

    @property
    def skill(self) -> dict[str, float | None] | None:
        """Each signal's skill against the naive predictors; None for a model trained
        before skill was measured."""
        skill = self.card.skill
        return None if skill is None else {k: v.skill for k, v in skill.items()}

    @property
    def unskilled(self) -> tuple[str, ...]:
        """The signals the model cannot predict: never judged."""
        return self.card.unskilled

    @cached_property
    def relations(self) -> Relations | None:
        """How the commands follow the motion on normal logs; None where the model has none
        (trained before they were learned, or the logs could not teach them)."""
        entry = self.card.entry("command_relations")
        return None if not entry or "weights" not in entry else relations_from_json(entry)

    @cached_property
    def effort(self) -> EffortModel | None:
        """Each actuator's normal share of its group's effort; None where the model has none
        (trained before effort was learnt, or the logs could not teach it)."""
        entry = self.card.entry("effort")
        return None if not entry or "groups" not in entry else EffortModel.from_json(entry)

    @property
    def command_names(self) -> tuple[str, ...]:
        return self.card.command_names

    @property
    def input_names(self) -> tuple[str, ...]:
        """The measured inputs that drive it beside the commands (none for most models)."""
        return self.card.input_names

    def drive(self, commands: np.ndarray, inputs: np.ndarray | None = None) -> np.ndarray:
        """The model's input rows for ``commands`` (steps, n_commands): with the measured
        ``inputs`` of the same steps, or where there are none (a simulated mission) each
        input at its typical value on the training logs."""
        typical = [i.typical for i in self.card.inputs]
        if not typical:
            return commands
        if inputs is None:
            inputs = np.tile(typical, (len(commands), 1))
        return np.hstack([commands, inputs])

    @property
    def sensor_names(self) -> tuple[str, ...]:
        return self.card.sensor_names


def default_model_dir(vehicle: str = "twin-burger") -> Path:
    """Where the shipped model of a vehicle (the profile's ``vehicle.name``) lives."""
    # The package is installed as files (see auvdiag_cli.vehicle.profile.BUILTIN_FOLDER).
    return Path(__file__).parent / vehicle.replace("-", "_")


def save_model(directory: Path, network: "RecurrentDynamics", normaliser: Normaliser,
               metadata: dict[str, Any], extra: dict[str, np.ndarray] | None = None) -> None:
    """Write weights and metadata; the metadata gains the architecture and weight digest.
    ``extra``: the other predictors' arrays (``linear``, ``linear_replay``, ``on_linear/…``)."""
    directory.mkdir(parents=True, exist_ok=True)
    weights = directory / WEIGHTS_FILE
    arrays = {k: v.detach().numpy().copy() for k, v in network.state_dict().items()}
    arrays |= extra or {}
    np.savez(weights, **arrays)  # type: ignore[arg-type]
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
    _write_card(ModelCard.from_document(full), directory)


def _write_card(card: ModelCard, directory: Path) -> None:
    """Write model.json as the card says it (``ModelCard.to_document``), atomic: a reader
    never sees half of it."""
    target = directory / METADATA_FILE
    temporary = target.with_name(f".{target.name}.tmp")
    temporary.write_text(json.dumps(card.to_document(), indent=2) + "\n", encoding="utf-8")
    os.replace(temporary, target)


def write_model(model: LoadedModel, directory: Path) -> None:
    """Write ``model``'s (updated) model.json into ``directory``; a directory other than
    the one it was read from gets its weights too."""
    source = model.directory
    if source is None or directory.resolve() != source.resolve():
        if source is None:
            raise ModelFileError(f"{model.path}: the model's weights are not in a directory "
                                 "to copy from")
        directory.mkdir(parents=True, exist_ok=True)
        for file in source.iterdir():
            if file.is_file() and file.name != METADATA_FILE and not file.name.startswith("."):
                (directory / file.name).write_bytes(file.read_bytes())
    _write_card(model.card, directory)


def _read_weights(directory: Path, version: int) -> dict[str, np.ndarray]:
    if version == 1:
        import torch

        state = torch.load(directory / LEGACY_WEIGHTS_FILE, map_location="cpu",
                           weights_only=True)
        return {k: v.numpy() for k, v in state.items()}
    with np.load(directory / WEIGHTS_FILE, allow_pickle=False) as archive:
        return {name: archive[name] for name in archive.files}


def trained_profile(directory: Path) -> Path | None:
    """The profile a model directory was trained with, as its model.json records it: a
    built-in profile's name, or its file (a ModelFileError where that file is gone); None
    where it records none or cannot be read (loading the model reports what is wrong)."""
    try:
        recorded = json.loads((directory / METADATA_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    where = recorded.get("profile") if isinstance(recorded, dict) else None
    if not isinstance(where, str) or not where:
        return None
    if where.startswith("builtin:"):
        return Path(where.removeprefix("builtin:"))
    if not Path(where).is_file():
        raise ModelFileError(f"{directory}: trained with the profile {where}, which is not "
                             "there: pass the vehicle's profile with --profile")
    return Path(where)


def load_model(directory: Path | None = None, vehicle: str = "twin-burger") -> LoadedModel:
    """Load a model directory, or when ``directory`` is None the model shipped for
    ``vehicle`` (a profile's ``vehicle.name``)."""
    label = f"builtin:{vehicle.replace('-', '_')}" if directory is None else str(directory)
    if directory is None:
        directory = default_model_dir(vehicle)
        if not (directory / METADATA_FILE).is_file():
            raise ModelFileError(f"no model is shipped for vehicle {vehicle!r}: train one "
                                 "with 'auvdiag train' and pass it with --model")
    meta_path = directory / METADATA_FILE
    if not meta_path.is_file() or not any((directory / name).is_file() for name in
                                          (WEIGHTS_FILE, LEGACY_WEIGHTS_FILE)):
        raise ModelFileError(f"{directory}: not a model directory "
                             f"(needs {METADATA_FILE} and {WEIGHTS_FILE})")
    try:
        metadata = json.loads(meta_path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        raise ModelFileError(f"{meta_path}: unreadable metadata: {error}") from None
    if metadata.get("format") != FORMAT_NAME:
        raise ModelFileError(f"{meta_path}: not an auvdiag model file")
    version = metadata.get("format_version")
    if version not in (1, FORMAT_VERSION):
        raise ModelFileError(f"{meta_path}: model format version {version} is not supported "
                             f"(this tool reads versions 1 to {FORMAT_VERSION})")
    try:
        arch, norm = metadata["architecture"], metadata["normalisation"]
        normaliser = Normaliser(tuple(norm["command_scale"]), tuple(norm["state_scale"]),
                                norm["delta_ratio"])
        arrays = _read_weights(directory, version)
        extra = {k: arrays.pop(k) for k in list(arrays)
                 if k in (LINEAR_KEY, LINEAR_REPLAY_KEY)
                 or k.startswith(ON_LINEAR_PREFIX)}
        model = LoadedModel(arrays, normaliser, ModelCard.from_document(metadata), label,
                            extra, directory)
        fast = model.fast        # checks every weight is there with the architecture's shape
        _ = model.dynamics       # and every predictor a signal is read from
        _ = model.effort         # and that an effort entry refits
        _ = model.relations      # and that the command relations fit the commands
        if (fast.hidden, fast.input_states.shape[0]) != (arch["hidden"], arch["n_states"]):
            raise ValueError("weights do not match the architecture in the metadata")
    except Exception as error:  # bad archives, pickle refusals, missing or misshapen weights
        raise ModelFileError(f"{directory}: model does not load: {error}") from None
    return model
