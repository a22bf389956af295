"""What model.json says of how far a model can be trusted: its horizon, its skill per signal
on held-out normal data (at that horizon and at every one tried), the predictor each signal
is read from and its held-out error, beside the paper's own where the vehicle is the
paper's."""

import math
from collections.abc import Sequence
from typing import Any

from auvdiag_cli.vehicle.profile import Profile
from models.skill import MIN_SCORED_SAMPLES, MIN_SKILL, SKILL_MARGIN, HorizonScore

# The paper's model errors after training (Takai & Ura 1999), for comparison in reports.
PAPER_MODEL_ERROR = {"flow": 0.0175, "yaw_rate": 0.0168}
PAPER_VEHICLE = "twin-burger"
SKILL_METHOD = ("skill = 1 - rms_model / min(rms_hold, rms_mean) on held-out normal data, "
                "replays re-starting every horizon from a median start state; versus_linear "
                "= 1 - rms_model / rms_linear")
PREDICTOR_METHOD = ("each signal is read from the predictor with the best held-out skill at "
                    "the horizon chosen: linear (least squares), linear-replay (the same "
                    "refined against the replay's error), network, or network-on-linear; "
                    "a later one must win by "
                    f"{SKILL_MARGIN} skill")
SKILL_THRESHOLD_REASON = (
    "a stuck or dead sensor leaves a residual of about rms_hold; it clears a threshold of "
    "1.5 x the normal g only if rms_hold / rms_model >= 1.5, i.e. skill >= 1/3")


def paper_model_error(profile: Profile) -> dict[str, float]:
    """The paper's figures, for the paper's vehicle only: no other vehicle is comparable."""
    return dict(PAPER_MODEL_ERROR) if profile.name == PAPER_VEHICLE else {}


def _skill_record(score: HorizonScore) -> dict[str, Any]:
    def number(value: float) -> float | None:
        return round(value, 6) if math.isfinite(value) else None

    return {"horizon_s": score.horizon_s, "signals": {
        name: {"skill": number(s.skill), "judged": s.judged, "samples": s.samples,
               "versus_linear": number(s.versus_linear), "model_rms": number(s.model_rms),
               **{f"{k}_rms": number(v) for k, v in s.baseline_rms.items()}}
        for name, s in score.signals.items()}}


def skill_metadata(scores: Sequence[HorizonScore], chosen: HorizonScore,
                   heldout_names: Sequence[str], profile: Profile) -> dict[str, Any]:
    """The model.json keys that say how far the model can be trusted: its horizon, its skill
    per signal at that horizon (and at every horizon tried), its held-out error."""
    record = _skill_record(chosen)["signals"]
    return {
        "horizon_s": chosen.horizon_s,        # null: the paper's free run
        "skill": {
            "method": SKILL_METHOD,
            "judged_from": round(MIN_SKILL, 4),
            "why": SKILL_THRESHOLD_REASON,
            "signals": {name: {"skill": record[name]["skill"], "judged": s.judged,
                               "samples": s.samples, "best_naive": s.best_naive,
                               "versus_linear": record[name]["versus_linear"]}
                        for name, s in chosen.signals.items()},
            "judged_from_samples": MIN_SCORED_SAMPLES,
            "horizons": [_skill_record(s) for s in scores],
        },
        "predictors": {
            "method": PREDICTOR_METHOD,
            "per_signal": dict(chosen.predictors),
        },
        "heldout_error": {
            "logs": list(heldout_names),
            "horizon_s": chosen.horizon_s,
            "rms": {name: record[name]["model_rms"] for name in chosen.signals},
            "paper_rms": paper_model_error(profile),
        },
    }
