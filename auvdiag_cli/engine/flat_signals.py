"""Sensors that read one value from the first sample to the last: reported and not judged,
because no residual of theirs says anything of the motion.

A channel the logger wrote but nothing fed (an airspeed sensor not fitted, a field the
autopilot fills with zero when it has no reading) reads one value throughout. The model
cannot tell such a log from a sensor that died before the log began, so it does not guess:
the signal is left unjudged in that log, and the report names it for the user to check.
The ALFA aircraft's airspeed, for one, reads 0.0 on whole flying days. Only a log long
enough to have moved (`MIN_FLAT_S`) is called flat.
"""

import numpy as np

MIN_FLAT_S = 10.0       # a shorter log may simply not have moved
FLAT_WHY = "a sensor not fitted, not logged or stuck"


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
