"""The sentences a report says, each written once: the terminal summary and the PDF's first
page both phrase a diagnosis with these, from the typed report."""

import math
from collections.abc import Mapping, Sequence

from auvdiag_cli.reports.report import (
    DegradationPart,
    HypothesesPart,
    HypothesisPart,
    Report,
    SubstitutionPart,
)


def names(components: Sequence[str]) -> str:
    """Components in words, joined by "or"."""
    return " or ".join(c.replace("_", " ") for c in components)


def by_reason(reasons: Mapping[str, str]) -> list[tuple[str, str]]:
    """Signals left out for the same reason, said once: (their names, the reason)."""
    grouped: dict[str, list[str]] = {}
    for name, why in reasons.items():
        grouped.setdefault(why, []).append(name)
    return [(", ".join(who), why) for why, who in grouped.items()]


def seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} s"


def onset_may_be_earlier(report: Report) -> bool:
    """The verdict's onset is the change test's, which may lie in its reference (the log's
    beginning it judges the rest against)."""
    change = report.change_check
    return change is not None and change.onset_in_reference and change.onset_s == report.onset_s


def give_or_take(error_s: float | None) -> str:
    """" (give or take 0.2 s)": the error the judge that dated the onset states."""
    return "" if error_s is None else f" (give or take {error_s:.1f} s)"


def when_sentence(report: Report) -> str:
    onset, detected = report.onset_s, report.detected_at_s
    if detected is None:
        return "no alarm"
    earlier = onset_may_be_earlier(report)
    delay = "" if onset is None else \
        f" (delay {detected - onset:.1f} s{' or more' if earlier else ''})"
    return (f"onset about {seconds(onset)}{' or earlier' if earlier else ''}"
            f"{give_or_take(report.onset_error_s)}, detected at "
            f"{seconds(detected)}{delay}")


def _hypothesis(h: HypothesisPart, margin: float | None = None) -> str:
    described = h.description      # reports saved before it: rebuilt from the kind
    if described is None:
        kind = (f"weakened to {h.thrust_fraction:.0%} thrust"
                if h.kind == "weakened" and h.thrust_fraction is not None else h.kind)
        described = f"{h.component.replace('_', ' ')} {kind}"
    said = ([f"ruled out: {h.ruled_out}"] if h.ruled_out else []) if (
        h.peak_g_over_threshold is None) else [
        f"g at most {h.peak_g_over_threshold:.0%} of its threshold"]
    if margin is not None and math.isfinite(margin):
        said.append(f"{margin:.1f}x the best's")
    return described + (f" ({', '.join(said)})" if said else "")


def hypotheses_sentence(test: HypothesesPart) -> str:
    """Which single fault explains the log best, and the runner-up (how many times more of
    its threshold it leaves)."""
    text = ("best explained by " if test.best.explains else
            "no single-component fault explains it; closest: ") + _hypothesis(test.best)
    if test.runner_up is not None:
        text += "; runner-up " + _hypothesis(test.runner_up, test.margin)
    return text


def thrust_kept(weak: DegradationPart) -> str:
    """"about 50 %" of its thrust, or "part" where the report does not say."""
    return "part" if weak.thrust_fraction is None else f"about {weak.thrust_fraction:.0%}"


def degradation_sentence(weak: DegradationPart) -> str:
    return f"{weak.component.replace('_', ' ')} gives {thrust_kept(weak)} of its thrust"


def substitution_facts(s: SubstitutionPart) -> list[tuple[str, str]]:
    """(label, sentence) of Substituting Control: what replaced the sensor, and against the
    truth and the mission where the report has them."""
    expected = ("" if s.expected_error_rms is None
                else f", expected error {s.expected_error_rms:.4f} {s.unit} rms")
    facts = [("Substituting Control", f"the model's {s.signal} replaces the sensor from "
              f"{seconds(s.from_s)}{expected}")]
    if s.truth_error_rms is not None and s.failed_sensor_error_rms is not None:
        facts.append(("Against the truth", f"substitute {s.truth_error_rms:.4f} {s.unit} "
                      f"rms, failed sensor {s.failed_sensor_error_rms:.4f} {s.unit} rms"))
    if s.track_end_error_m:
        facts.append(("Dead-reckoned end", ", ".join(
            f"{k} {v:.2f} m from the truth" for k, v in s.track_end_error_m.items()
            if v is not None)))
    loop = s.closed_loop
    if loop is not None:
        outcome = (f"reaches the last waypoint at {seconds(loop.finished_s)}" if
                   loop.reached_last_waypoint else "does not reach the last waypoint")
        miss = "" if loop.miss_m is None else f", ending {loop.miss_m:.2f} m from it"
        facts.append(("Closed-loop replay", f"fed the model from {seconds(loop.from_s)}, "
                      f"the controller {outcome}{miss}"))
    return facts


def model_sentence(report: Report) -> str:
    model = report.model
    text = f"{model.name} for {model.vehicle}, created {model.created}"
    if model.heldout_error_rms:
        text += "; held-out error " + ", ".join(
            f"{k} {v:.4f} {report.units.get(k, '')}".rstrip()
            for k, v in model.heldout_error_rms.items() if v is not None)
    if model.inputs:
        text += "; driven by the commands and the measured " + ", ".join(model.inputs)
    text += ("; free-running replay" if model.horizon_s is None
             else f"; replay re-started every {model.horizon_s:g} s")
    budget = model.false_alarm_rate
    text += (f"; thresholds set for {budget.rate:g} false alarms per {budget.per}" if budget
             else "; thresholds calibrated on normal logs" if model.thresholds_calibrated
             else "; thresholds not calibrated: the profile's, or 1.5 x the g of the logs "
                  "held out of training where that is more")
    return text
