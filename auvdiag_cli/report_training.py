"""What `auvdiag train` prints: where the model went, its skill per signal against the naive
predictors, the horizon chosen, and the paper's figures for the paper's vehicle only."""

import math

from auvdiag_cli.training_job import TrainingResult
from models.skill import MIN_SKILL, HorizonScore


def horizon_text(horizon_s: float | None) -> str:
    return "free run" if horizon_s is None else f"{horizon_s:g} s"


def _number(value: float) -> str:
    return f"{value:9.4f}" if math.isfinite(value) else f"{value!s:>9}"


def _skill_rows(score: HorizonScore) -> list[str]:
    baselines = list(next(iter(score.signals.values())).baseline_rms)
    rows = [f"  {'signal':<14}{'skill':>7}{'vs linear':>10}{'model':>10}"
            + "".join(f"{name:>10}" for name in baselines) + "   judged"]
    for name, s in score.signals.items():
        verdict = "yes" if s.judged else "NO: not judged (the model cannot predict it)"
        rows.append(f"  {name:<14}{s.skill:7.2f}{s.versus_linear:10.2f} {_number(s.model_rms)}"
                    + "".join(f" {_number(s.baseline_rms[b])}" for b in baselines)
                    + f"   {verdict}")
    return rows


def training_lines(result: TrainingResult, paper_rms: dict[str, float]) -> list[str]:
    chosen = result.chosen
    lines = [f"model {'written to ' + str(result.output) if result.written else 'NOT written'}"
             f" ({result.training_logs} training log(s), {result.operating_hours:.2f} h of "
             f"operating time; held out: {result.heldout_split})"]
    tried = ", ".join(f"{horizon_text(s.horizon_s)} {len(s.judged)}/{len(s.signals)}"
                      for s in result.scores)
    lines.append(f"prediction horizon: {horizon_text(chosen.horizon_s)}"
                 + (f" (signals judged per horizon tried: {tried})" if len(result.scores) > 1
                    else ""))
    lines.append("skill on held-out normal data = 1 - rms_model / the better naive rms "
                 f"(the last value holds, the training mean), judged from {MIN_SKILL:.2f}; "
                 "vs linear: the same against a least-squares linear model. rms in the "
                 "signals' units:")
    lines += _skill_rows(chosen)
    if paper_rms:
        lines.append("the paper's model error for this vehicle (rms): "
                     + ", ".join(f"{k} {v}" for k, v in paper_rms.items()))
    return lines
