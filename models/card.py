"""The model card: what ``model.json`` says about a model, parsed once when it loads into
typed, read-only values, and the one writer of that document (``to_document``). Everything
outside ``models`` reads a model through its card (and the parsed relations and effort
beside it), never through the JSON document; a missing key takes the value a model from
before that key existed means. A writer (train, calibrate, relate, score) gives the card new
entries as typed values that say their own JSON (``ModelEntry``) and gets a new card."""

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Protocol, runtime_checkable

from models.ahead import AheadPredictor
from models.change_training import ChangeTraining
from models.fast import NETWORK
from models.tracking import TrackingFit


@runtime_checkable
class ModelEntry(Protocol):
    """A typed value that is one entry of model.json."""

    def to_json(self) -> Mapping[str, object]: ...


@dataclass(frozen=True)
class ModelInput:
    """A measured input that drives the model beside the commands."""

    name: str
    unit: str
    typical: float            # its median on the training logs (held there in simulations)
    # Whether a training log fed it (moved it); one none did, the model never learnt how it
    # acts, and every diagnosis holds it at ``typical`` (models trained before: fed).
    fed: bool = True


@dataclass(frozen=True)
class SignalSkillRecord:
    skill: float | None       # None: not measured (a diverged predictor)
    judged: bool
    samples: int | None       # held-out samples the figure comes from
    versus_linear: float | None = None   # the same against the least-squares linear model


@dataclass(frozen=True)
class FalseAlarmSetting:
    """The false-alarm budget calibrate set the thresholds for."""

    rate: float
    per: str                  # "log" or "hour"

    def as_dict(self) -> dict[str, float | str]:
        return {"rate": self.rate, "per": self.per}


def _ahead(meta: Mapping[str, Any], n_commands: int, n_sensors: int, n_inputs: int
           ) -> AheadPredictor | None:
    entry = meta.get("ahead_predictor") or {}
    return None if "weights" not in entry else AheadPredictor.from_json(
        entry, n_commands, n_sensors, n_inputs)


def _change_stride(entry: Mapping[str, Any]) -> int | None:
    stride = entry.get("stride_steps")
    if stride is None:
        return None
    if int(stride) != stride or stride < 1:
        raise ValueError(f"change_test stride_steps {stride!r} is not a whole number of steps")
    return int(stride)


def _way_scales(entry: Mapping[str, Any]) -> Mapping[str, Mapping[str, tuple[float, float]]]:
    scales = {}
    for statistic, values in (entry.get("way_scales") or {}).items():
        pairs = {}
        for name, pair in values.items():
            above, below = (float(v) for v in pair)
            if not (above > 0 and below > 0):
                raise ValueError(f"change_test way_scales {statistic} {name} {pair!r} are not "
                                 "two positive numbers")
            pairs[str(name)] = (above, below)
        scales[str(statistic)] = _frozen(pairs)
    return _frozen(scales)


def _optional_float(value: object) -> float | None:
    return None if value is None else float(value)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Refused:
    """Why something was not learned from the logs (model.json keeps ``{"refused": …}``)."""

    reason: str

    def to_json(self) -> dict[str, str]:
        return {"refused": self.reason}


@dataclass(frozen=True)
class StartReference:
    """Where normal logs recorded from rest start, and how far a start may lie from it
    (None: that sensor's normal starts scatter too much to judge); or why there is none."""

    reference: tuple[float, ...] = ()
    thresholds: tuple[float | None, ...] = ()
    training_starts: tuple[tuple[float | None, ...], ...] = ()
    refused: str | None = None
    span_s: float = 0.0                 # the start: the logs' first span_s seconds
    spread: tuple[float, ...] = ()      # rms of the training starts about the reference
    logs: int = 0                       # training starts
    heldout_logs: int = 0               # held-out starts that set the thresholds

    @property
    def usable(self) -> bool:
        return bool(self.reference)

    def to_json(self) -> dict[str, object]:
        """model.json's ``start_state`` entry."""
        if self.refused is not None:
            return {"refused": self.refused}
        return {"span_s": self.span_s, "reference": list(self.reference),
                "thresholds": list(self.thresholds), "spread": list(self.spread),
                "logs": self.logs, "heldout_logs": self.heldout_logs,
                # calibrate --false-alarm-rate fits each start's law to these as well
                "training_starts": [list(row) for row in self.training_starts]}

    @classmethod
    def from_json(cls, entry: Mapping[str, Any]) -> "StartReference":
        return cls(tuple(float(v) for v in entry.get("reference", [])),
                   tuple(_optional_float(t) for t in entry.get("thresholds", [])),
                   tuple(tuple(_optional_float(v) for v in row)
                         for row in entry.get("training_starts", [])),
                   entry.get("refused"), float(entry.get("span_s", 0.0)),
                   tuple(float(v) for v in entry.get("spread", [])),
                   int(entry.get("logs", 0)), int(entry.get("heldout_logs", 0)))


@dataclass(frozen=True)
class ModelIdentity:
    """What a report says about the model that judged a log."""

    name: str | None
    vehicle: str | None
    path: str
    weights_sha256: str | None
    created: str | None
    heldout_error_rms: Mapping[str, float | None] | None
    horizon_s: float | None
    skill: Mapping[str, float | None] | None
    predictors: Mapping[str, str]
    inputs: tuple[str, ...]
    thresholds_calibrated: bool
    false_alarm_rate: FalseAlarmSetting | None
    # How many of calibrate's normal logs the model had not been trained on (None: not
    # calibrated, or calibrated before it was kept): what its thresholds rest on.
    calibration_unseen_logs: int | None = None

    def as_dict(self) -> dict[str, object]:
        """The JSON report's ``model`` object."""
        return {"name": self.name, "vehicle": self.vehicle, "path": self.path,
                "weights_sha256": self.weights_sha256, "created": self.created,
                "heldout_error_rms": _plain(self.heldout_error_rms),
                "horizon_s": self.horizon_s, "skill": _plain(self.skill),
                "predictors": dict(self.predictors), "inputs": list(self.inputs),
                "thresholds_calibrated": self.thresholds_calibrated,
                "false_alarm_rate": None if self.false_alarm_rate is None
                else self.false_alarm_rate.as_dict()}


def _plain(mapping: Mapping[str, float | None] | None) -> dict[str, float | None] | None:
    return None if mapping is None else dict(mapping)


def _frozen(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(mapping))


def _limits(table: Mapping[str, Any]) -> Mapping[str, Mapping[str, float]]:
    """statistic -> signal -> threshold, as model.json keeps the change test's."""
    return _frozen({str(statistic): _frozen({str(k): float(v) for k, v in values.items()})
                    for statistic, values in table.items()})


@dataclass(frozen=True)
class ModelCard:
    name: str | None
    vehicle: str | None
    created: str | None
    dt_s: float
    command_names: tuple[str, ...]
    sensor_names: tuple[str, ...]
    inputs: tuple[ModelInput, ...]
    hidden: int
    drive_width: int                  # the network's inputs: the commands, then the inputs
    weights_sha256: str | None
    horizon_s: float | None                               # None: the paper's free run
    predictors: Mapping[str, str]                          # signal -> predictor it is read from
    skill: Mapping[str, SignalSkillRecord] | None          # None: trained before skill
    judged_from_samples: int
    heldout_error_rms: Mapping[str, float | None]
    heldout_logs: tuple[str, ...]                          # the logs skill was measured on
    full_scale: Mapping[str, float] | None                 # None: the profile's
    window_samples: int | None                             # None: the profile's
    thresholds: Mapping[str, Mapping[str, float]] | None   # mode -> signal -> g; None: profile's
    calibrated: bool
    false_alarm_rate: FalseAlarmSetting | None
    training_digests: frozenset[str]                       # sha256 of each training log
    start_state: StartReference
    relations_refused: str | None                          # why no command relations
    effort_refused: str | None                             # why no effort model
    # The change test's thresholds, statistic -> signal (`engine.change_check`); empty:
    # calibrate has not set them, and the test is not run.
    change_thresholds: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    # The steps between the windows they were set on (None: windows side by side, as
    # calibrate set them before it judged a window every step).
    change_stride: int | None = None
    # statistic -> signal -> (above, below): how far normal logs go each way, each way's
    # statistic divided by its own before they are judged (none: either way alike).
    change_way_scales: Mapping[str, Mapping[str, tuple[float, float]]] = field(
        default_factory=dict)
    # input -> statistic -> signal: thresholds for a log that does not feed that input,
    # where they are higher (`jobs.change_unfed`; none: calibrated before).
    change_unfed: Mapping[str, Mapping[str, Mapping[str, float]]] = field(
        default_factory=dict)
    # signal -> how long calibrate's normal logs let the change test judge it, all
    # together, where too little to set it thresholds (it has none).
    change_too_brief: Mapping[str, float] = field(default_factory=dict)
    # How many normal logs (calibrate's and those trained on) set those thresholds (None:
    # not recorded, calibrated before it was kept).
    change_logs: int | None = None
    # The change test's predictor a moment ahead (`models.ahead`); None: a model trained
    # without it, whose change test judges the replay's error.
    ahead: AheadPredictor | None = None
    # The change test's largest statistics on the logs trained on (none: trained before).
    change_training: ChangeTraining = field(default_factory=ChangeTraining)
    # The UTC days of the normal logs calibrate set the thresholds on (none: not known).
    calibration_days: tuple[str, ...] = ()
    # Of those logs, how many the model was not trained on (None: not calibrated, or not
    # known).
    calibration_unseen_logs: int | None = None
    # The controller's loops whose gain the change test judges (`models.tracking`).
    tracking: tuple[TrackingFit, ...] = ()
    # signal -> the largest |value| the logs it learnt from reached (`engine.envelope`;
    # none: trained before it was kept).
    envelope: Mapping[str, float] = field(default_factory=dict)
    # model.json as the card writes it back: every entry, the records kept for people
    # (how it was trained and calibrated) among them, as JSON text so that it stays frozen.
    document_text: str = field(default="{}", repr=False, compare=False)

    def to_document(self) -> dict[str, Any]:
        """model.json: what the card was read from, with every entry given since."""
        document: dict[str, Any] = json.loads(self.document_text)
        return document

    def entry(self, key: str) -> dict[str, Any]:
        """One entry of the document (a copy; empty where the model has none), for the
        parsers in ``models`` of what the card does not type itself."""
        value = self.to_document().get(key)
        return value if isinstance(value, dict) else {}

    def with_entries(self, **entries: "ModelEntry | Mapping[str, object] | object"
                     ) -> "ModelCard":
        """The card with these entries replaced, each a typed value (written with its
        ``to_json``) or plain JSON; this card is unchanged."""
        document = self.to_document()
        for key, value in entries.items():
            plain = value.to_json() if isinstance(value, ModelEntry) else value
            document[key] = json.loads(json.dumps(plain))
        return ModelCard.from_document(document)

    def change_thresholds_without(self, missing: Sequence[str]
                                  ) -> dict[str, dict[str, float]]:
        """The change test's thresholds for a log that does not feed the inputs ``missing``:
        the larger of the fed ones and each missing input's (`change_unfed`)."""
        result = {statistic: dict(values) for statistic, values in self.change_thresholds.items()}
        for name in missing:
            for statistic, values in self.change_unfed.get(name, {}).items():
                for signal, value in values.items():
                    if signal in result.get(statistic, {}):
                        result[statistic][signal] = max(result[statistic][signal], value)
        return result

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(i.name for i in self.inputs)

    @property
    def unskilled(self) -> tuple[str, ...]:
        """The signals the model cannot predict: never judged."""
        skill = self.skill or {}
        return tuple(n for n in self.sensor_names if n in skill and not skill[n].judged)

    def identity(self, path: str) -> ModelIdentity:
        return ModelIdentity(
            self.name, self.vehicle, path, self.weights_sha256, self.created,
            _frozen(self.heldout_error_rms) if self.heldout_error_rms else None,
            self.horizon_s,
            None if self.skill is None else _frozen({k: v.skill for k, v in self.skill.items()}),
            self.predictors, self.input_names, self.calibrated, self.false_alarm_rate,
            self.calibration_unseen_logs)

    @classmethod
    def from_document(cls, meta: Mapping[str, Any]) -> "ModelCard":
        """Parse model.json (raises KeyError, TypeError or ValueError where it is malformed:
        the loader names the file)."""
        signals = meta["signals"]
        sensors = tuple(str(s["name"]) for s in signals["sensors"])
        skill = meta.get("skill", {}).get("signals")
        chosen = meta.get("predictors", {}).get("per_signal", {})
        calibration, change = meta.get("calibration") or {}, meta.get("change_test") or {}
        budget = calibration.get("false_alarm_budget")
        return cls(
            name=meta.get("name"), vehicle=meta.get("vehicle"), created=meta.get("created"),
            dt_s=float(meta["dt_s"]),
            command_names=tuple(str(c) for c in signals["commands"]),
            sensor_names=sensors,
            inputs=tuple(ModelInput(str(i["name"]), str(i.get("unit", "")), float(i["typical"]),
                                    bool(i.get("fed", True)))
                         for i in signals.get("inputs", [])),
            hidden=int(meta["architecture"]["hidden"]),
            drive_width=int(meta["architecture"]["n_commands"]),
            weights_sha256=meta.get("weights_sha256"),
            horizon_s=_optional_float(meta.get("horizon_s")),
            predictors=_frozen({n: str(chosen.get(n, NETWORK)) for n in sensors}),
            skill=None if skill is None else _frozen({
                name: SignalSkillRecord(_optional_float(r.get("skill")),
                                        bool(r.get("judged", False)), r.get("samples"),
                                        _optional_float(r.get("versus_linear")))
                for name, r in skill.items()}),
            judged_from_samples=int(meta.get("skill", {}).get("judged_from_samples", 0)),
            heldout_error_rms=_frozen({k: _optional_float(v) for k, v in
                                       meta.get("heldout_error", {}).get("rms", {}).items()}),
            heldout_logs=tuple(str(n) for n in meta.get("heldout_error", {}).get("logs", [])),
            full_scale=None if "full_scale" not in meta else _frozen(
                {k: float(v) for k, v in meta["full_scale"].items()}),
            window_samples=None if "window_samples" not in meta else int(meta["window_samples"]),
            thresholds=None if not meta.get("thresholds") else _frozen({
                mode: _frozen({k: float(v) for k, v in values.items()})
                for mode, values in meta["thresholds"].items()}),
            calibrated="calibration" in meta,
            false_alarm_rate=None if not budget else FalseAlarmSetting(float(budget["rate"]),
                                                                       str(budget["per"])),
            training_digests=frozenset(str(e.get("sha256")) for e in
                                       meta.get("training", {}).get("logs", [])),
            start_state=StartReference.from_json(meta.get("start_state") or {}),
            relations_refused=(meta.get("command_relations") or {}).get("refused"),
            effort_refused=(meta.get("effort") or {}).get("refused"),
            **_change_test(change),
            ahead=_ahead(meta, len(signals["commands"]), len(sensors),
                         len(signals.get("inputs", []))),
            change_training=ChangeTraining.from_json(meta.get("change_training") or {}),
            calibration_days=tuple(str(day) for day in calibration.get("days", [])),
            calibration_unseen_logs=_unseen(calibration),
            tracking=tuple(TrackingFit.from_json(t) for t in meta.get("tracking") or []),
            envelope=_envelope(meta.get("envelope") or {}),
            document_text=json.dumps(meta))


def _change_test(change: Mapping[str, Any]) -> dict[str, Any]:
    """The card's fields read from model.json's `change_test` entry."""
    count = change.get("normal_logs")
    return {"change_thresholds": _limits(change.get("thresholds", {})),
            "change_stride": _change_stride(change), "change_way_scales": _way_scales(change),
            "change_unfed": _frozen({str(i): _limits(by) for i, by in change.get(
                "unfed_thresholds", {}).items()}),
            "change_too_brief": {str(n): float(v) for n, v in (
                change.get("judged_too_briefly_s") or {}).items()},
            "change_logs": None if count is None else int(count)}


def _unseen(calibration: Mapping[str, Any]) -> int | None:
    """How many of calibrate's normal logs the model was not trained on (None: no record)."""
    if "normal_logs" not in calibration or "in_sample_logs" not in calibration:
        return None
    return len(calibration["normal_logs"]) - len(calibration["in_sample_logs"])


def _envelope(entry: Mapping[str, Any]) -> Mapping[str, float]:
    """model.json's `envelope`: signal -> the largest |value| the model learnt from (a
    value that is no positive number bounds nothing: left out)."""
    values = {str(k): float(v) for k, v in entry.get("sensors", {}).items()}
    return _frozen({k: v for k, v in values.items() if math.isfinite(v) and v > 0})
