"""Sensors that read one value from the first sample to the last: reported, because what is
judged of them says nothing of the motion.

A channel the logger wrote but nothing fed (an airspeed sensor not fitted, a field the
autopilot fills with zero when it has no reading) reads one value throughout. The model
cannot tell such a log from a sensor that died before the log began, and a user who maps
the channel should know which it sees: the ALFA aircraft's airspeed, for one, reads 0.0 on
whole flying days. Only a log long enough to have moved (`MIN_FLAT_S`) is called flat.
"""

import numpy as np

MIN_FLAT_S = 10.0       # a shorter log may simply not have moved


def flat_sensor_notes(sensors: np.ndarray, names: tuple[str, ...], dt_s: float) -> list[str]:
    """One note per sensor whose samples (at least `MIN_FLAT_S` of them) are all alike."""
    notes = []
    for column, name in enumerate(names):
        values = sensors[:, column][np.isfinite(sensors[:, column])]
        if len(values) * dt_s >= MIN_FLAT_S and values.min() == values.max():
            notes.append(f"{name} reads {values[0]:g} throughout the log ({len(values)} "
                         "samples): a sensor not fitted, not logged or stuck; what is judged "
                         "of it says nothing of the motion")
    return notes
