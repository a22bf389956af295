"""Sensors that read one value from the first sample to the last: reported and not judged,
because no residual of theirs says anything of the motion.

A channel the logger wrote but nothing fed (an airspeed sensor not fitted, a field the
autopilot fills with zero when it has no reading) reads one value throughout. The model
cannot tell such a log from a sensor that died before the log began, so it does not guess:
the signal is left unjudged in that log, and the report names it for the user to check.
The ALFA aircraft's airspeed, for one, reads 0.0 on whole flying days. Only a log long
enough to have moved (`MIN_FLAT_S`) is called flat. A measured input that reads one value
throughout drives the model at its typical value on the normal logs instead (`held_at`): as
logged, a channel filled with zeros would drive it far from anything it learnt.
"""

from collections.abc import Mapping, Sequence

import numpy as np

MIN_FLAT_S = 10.0       # a shorter log may simply not have moved
FLAT_WHY = "a sensor not fitted, not logged or stuck"
ABSENT = "is not in this log"     # a measured input the log lacks altogether
FLAT_INPUT_WHY = ("an input not fitted, not logged or stuck: the model is driven by its "
                  "typical value on normal logs instead")


def flat_sensors(sensors: np.ndarray, names: tuple[str, ...], dt_s: float) -> dict[str, str]:
    """Sensor -> what it reads, for each whose samples (at least `MIN_FLAT_S` of them) are
    all alike."""
    flat = {}
    for column, name in enumerate(names):
        values = sensors[:, column][np.isfinite(sensors[:, column])]
        if len(values) * dt_s >= MIN_FLAT_S and values.min() == values.max():
            flat[name] = f"reads {values[0]:g} throughout the log ({len(values)} samples)"
    return flat


def flat_sensor_notes(flat: dict[str, str]) -> list[str]:
    """One note per flat sensor (`flat_sensors`)."""
    return [f"{name} {reads}: {FLAT_WHY}" for name, reads in flat.items()]


def not_judged_flat(flat: dict[str, str]) -> dict[str, str]:
    """The reason a report prints for each flat sensor (`flat_sensors`) it leaves unjudged."""
    return {name: f"not judged ({reads}: {FLAT_WHY})" for name, reads in flat.items()}


def flat_input_notes(flat: dict[str, str]) -> list[str]:
    """One note per flat measured input (`flat_sensors` of the inputs)."""
    return [f"{name} {reads}: {FLAT_INPUT_WHY}" for name, reads in flat.items()]


def held_at(drive: np.ndarray, input_names: Sequence[str], flat: Mapping[str, object],
            typical: Mapping[str, float]) -> np.ndarray:
    """The model's drive (the commands, then the measured inputs ``input_names``) with each
    ``flat`` input held at its ``typical`` value."""
    held = drive.copy()
    first = drive.shape[1] - len(input_names)
    for k, name in enumerate(input_names):
        if name in flat and name in typical:
            held[:, first + k] = typical[name]
    return held


def typical_inputs(drives: Sequence[np.ndarray], input_names: Sequence[str],
                   flat: Sequence[Mapping[str, object]]) -> dict[str, float]:
    """Each measured input's median over the logs that fed it (``flat``: each log's flat
    inputs); an input no log fed has none."""
    first = drives[0].shape[1] - len(input_names) if drives else 0
    typical = {}
    for k, name in enumerate(input_names):
        fed = [d[:, first + k] for d, f in zip(drives, flat, strict=True) if name not in f]
        values = np.concatenate(fed) if fed else np.zeros(0)
        if np.isfinite(values).any():
            typical[name] = float(np.nanmedian(values))
    return typical
