"""How the signals are judged, worked out once per model and profile and shared by the
diagnosis, the hypothesis test, the isolation and the fault signatures (one context: the
profile as calibrated and the model travel in it together): each signal's full scale R_i, g's
window K, the decision window, the thresholds per mode (calibrated into the model over
the profile's defaults), and which signals the model has the skill to judge."""

from dataclasses import dataclass, replace

import numpy as np

from auvdiag_cli.engine.detection import binary_vector, decided_b, first_alarm
from auvdiag_cli.engine.residuals import residual_index
from auvdiag_cli.vehicle.profile import Profile
from models.store import LoadedModel

NOT_JUDGED = "not judged (the model cannot predict it)"


@dataclass(frozen=True)
class Judging:
    sensor_names: tuple[str, ...]
    full_scale: dict[str, float]         # R_i by signal
    window: int                          # K, samples of g's mean
    decision_steps: int                  # b is collected this long after the first alarm
    profile: Profile                     # with the thresholds calibrated into the model
    not_judged: dict[str, str]           # signal -> why the replay does not judge it
    model: LoadedModel                   # the model it judges with
    # Signals no judge takes in this log (a sensor it never fed): the change test neither.
    set_aside: frozenset[str] = frozenset()

    @classmethod
    def of(cls, model: LoadedModel, profile: Profile) -> "Judging":
        card = model.card
        judged = (profile if not card.thresholds else replace(profile, thresholds={
            **profile.thresholds, **{m: dict(v) for m, v in card.thresholds.items()}}))
        return cls(profile.sensor_names,
                   dict(profile.full_scales if card.full_scale is None else card.full_scale),
                   profile.window_samples if card.window_samples is None
                   else card.window_samples,
                   round(profile.decision_window_s / profile.dt_s), judged,
                   replay_left_out(model, profile), model)

    def without(self, reasons: dict[str, str]) -> "Judging":
        """This judging with ``reasons``' signals set aside by every judge (a log's own
        reasons: a sensor it never fed)."""
        return replace(self, not_judged={**self.not_judged, **reasons},
                       set_aside=self.set_aside | frozenset(reasons))

    @property
    def scales(self) -> np.ndarray:
        return np.asarray([self.full_scale[name] for name in self.sensor_names])

    @property
    def judged_mask(self) -> np.ndarray:
        return np.asarray([name not in self.not_judged for name in self.sensor_names])

    @property
    def judged(self) -> list[str]:
        """The signals the replay judges."""
        return [name for name in self.sensor_names if name not in self.not_judged]

    def g(self, measured: np.ndarray, modelled: np.ndarray) -> np.ndarray:
        return residual_index(measured, modelled, self.scales, self.window)

    def decided_b(self, measured: np.ndarray, modelled: np.ndarray,
                  thresholds: dict[str, float]) -> dict[str, int]:
        """The b a run of ``measured`` against ``modelled`` decides at its first alarm
        under one mode's ``thresholds`` (all zero when it never alarms)."""
        g = self.g(measured, modelled)
        b = binary_vector(g, np.tile([thresholds[n] for n in self.sensor_names], (len(g), 1)))
        alarm = first_alarm(b)
        bits = (np.zeros(len(self.sensor_names), bool) if alarm is None
                else decided_b(b, alarm, self.decision_steps))
        return {name: int(bits[i]) for i, name in enumerate(self.sensor_names)}


def own_log_only(profile: Profile) -> dict[str, str]:
    """The signals the profile has judged only against the log's own beginning (the change
    test), with the reason reports print; those judged only within a part's signature
    there, or only below the prediction, say so."""
    return {s.name: (f"judged only within a part's signature against the log's own "
                     f"beginning ({s.signature_only})" if s.signature_only else
                     f"judged only against the log's own beginning ({s.own_log_only})"
                     + (f", only below the prediction ({s.below_only})" if s.below_only else ""))
            for s in profile.sensors if s.own_log_only or s.signature_only}


def nothing_judged(judging: Judging, change_test: str | None) -> str:
    """Why no signal is judged, for a log the replay judges nothing in and the change test
    (``change_test``: how it describes itself, None: calibrate set it no threshold) does
    not judge."""
    left = sum(name in judging.not_judged for name in own_log_only(judging.profile))
    if not left:
        return "no signal is judged: the model cannot predict any of them"
    brief = judging.model.card.change_too_brief
    return (f"no signal is judged: {left} of {len(judging.sensor_names)} are judged only "
            "against the log's own beginning, by the change test, and " + (
                "it is " + change_test if change_test is not None else
                "calibrate's normal logs let it judge them too briefly to set its thresholds "
                f"({max(brief.values()):.1f} s in all at most; calibrate on more or longer "
                "normal logs)" if brief and judging.model.card.calibrated else
                "it is not calibrated (run `auvdiag calibrate` on normal logs)"))


def replay_left_out(model: LoadedModel, profile: Profile) -> dict[str, str]:
    """The signals the replay does not judge with this model and profile, each with why:
    no skill, or judged only against the log's own beginning."""
    return not_judged_signals(model) | own_log_only(profile)


def replay_judged(model: LoadedModel, profile: Profile) -> list[str]:
    """The signals the replay judges with this model and profile."""
    left_out = replay_left_out(model, profile)
    return [name for name in profile.sensor_names if name not in left_out]


def skilled(model: LoadedModel, profile: Profile) -> list[str]:
    """The signals the model has the skill to judge, by the replay or only against the
    log's own beginning: what the change test may judge with a model that has no
    predictor a moment ahead."""
    return [name for name in profile.sensor_names if name not in not_judged_signals(model)]


def unpredicted(model: LoadedModel) -> dict[str, str]:
    """The signals the model has no skill for, each with its skill ("unmeasured": none)."""
    signals = model.card.skill or {}
    return {name: "unmeasured" if signals[name].skill is None else f"{signals[name].skill:.2f}"
            for name in model.unskilled}


def not_judged_signals(model: LoadedModel) -> dict[str, str]:
    """The signals the model has no skill for, with the reason reports print."""
    signals, needed = model.card.skill or {}, model.card.judged_from_samples
    reasons = {}
    for name in model.unskilled:
        record = signals[name]
        if record.samples is not None and record.samples < needed:
            reasons[name] = (f"not judged (too little held-out data to measure the model's "
                             f"skill: {record.samples} samples, needs {needed})")
        else:
            skill = record.skill
            reasons[name] = NOT_JUDGED + ("" if skill is None else f" (skill {skill:.2f})")
    return reasons
