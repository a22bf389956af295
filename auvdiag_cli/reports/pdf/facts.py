"""What the first page of a dive report says, in words, from the report."""

import numpy as np

from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.sentences import (
    by_reason,
    degradation_sentence,
    hypotheses_sentence,
    model_sentence,
    names,
    seconds,
    substitution_facts,
    thrust_kept,
    when_sentence,
)
from auvdiag_cli.reports.series import Series


def summary_facts(report: Report) -> list[tuple[str, str]]:
    """(label, value) pairs, most important first."""
    facts = [("Log", f"{report.log} ({report.format}, {seconds(report.duration_s)}, "
              f"vehicle {report.vehicle})")]
    if report.verdict == "fault":
        if report.component:
            facts.append(("Component", report.component.replace("_", " ")))
        else:
            facts.append(("Candidates", names(report.candidates)
                          or "none: b fits no row of the pattern table"))
        facts.append(("When", when_sentence(report)))
    b = " ".join(f"{k}={v}" for k, v in report.b.items())
    facts.append(("Pattern table", f"case {report.case}, b = {b}" if report.case is not None
                  else f"b = {b}: no row names the part; named from the other evidence"
                  if report.component else f"b = {b} fits no row"))
    if report.hypotheses:
        facts.append(("Hypotheses", hypotheses_sentence(report.hypotheses)))
    if report.autopilot:
        facts.append(("Autopilot said", report.autopilot.summary))
    if report.coverage:
        facts.append(("Judged", report.coverage.summary))
    if report.not_judged:
        facts.append(("Not judged by the replay", "; ".join(
            f"{who}: {why}" for who, why in by_reason(report.not_judged))))
    if report.commands_check:
        facts.append(("Commands vs motion", report.commands_check.summary))
    if report.actuators and report.actuators.judged:
        facts.append(("Effort shares", report.actuators.summary))
    if report.start_check and report.start_check.judged:
        facts.append(("Start", report.start_check.summary))
    if report.change_check:
        facts.append(("Against its beginning", report.change_check.summary))
    if report.degradation:
        facts.append(("Partial failure", degradation_sentence(report.degradation)))
    active = report.active_diagnosis
    if active and active.recommended_dms:
        facts.append(("Next dive", "run " + " or ".join(active.recommended_dms)
                      + " to tell the candidates apart"))
    if report.substitution:
        facts += substitution_facts(report.substitution)
    routine = sum(1 for s in report.segments if s.mode == "routine")
    facts.append(("Segments", f"{len(report.segments)} ({routine} Diagnosis Motion "
                  f"Sequences), from the log's {report.segment_source}"))
    facts.append(("Model", model_sentence(report)))
    return facts


def _margin(report: Report, series: Series | None) -> str:
    """How close the healthy stretch of the log came to an alarm."""
    caveat = "; currents, a tether or a changed payload would raise g like a fault"
    if series is None or "g_percent" not in series:
        return "not checked (no time histories with this report)"
    time_s, names = series["time_s"], [str(n) for n in series["sensor_names"]]
    onset = report.onset_s
    healthy = time_s < onset if onset is not None else np.ones(time_s.shape, bool)
    judged = np.array([name not in report.not_judged for name in names])
    if not judged.any():
        return ("the replay judges no signal: see how the log compares with its own beginning"
                if report.change_check is not None else "no signal is judged")
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = series["g_percent"][healthy] / series["thresholds"][healthy]
    ratio[:, ~judged] = np.nan          # an unjudged signal's g is no margin to an alarm
    if not np.isfinite(ratio).any():
        return "no healthy stretch long enough to judge before the onset"
    row, column = np.unravel_index(np.nanargmax(ratio), ratio.shape)
    where = "before the onset" if onset is not None else "in the whole log"
    return (f"{where}, g peaked at {ratio[row, column]:.0%} of its threshold ({names[column]} "
            f"at {time_s[healthy][row]:.1f} s){caveat}")


def _single_fault(report: Report) -> str:
    if report.verdict != "fault":
        return "nothing was found to fail"
    if report.case is None and report.component:
        return ("no row of the pattern table names the part: it was named from the other "
                "evidence (what changed and the parts that move it, the hypotheses), which "
                "two faults at once could mislead too")
    if report.case is None:
        return ("b fits no row of the pattern table: more than one fault, or one the table "
                "does not describe; the verdict names no component")
    return f"b fits case {report.case} of the table; two faults at once could mimic it"


def _total_failure(report: Report) -> str:
    weak = report.degradation
    if weak:
        return (f"not so here: {weak.component.replace('_', ' ')} kept {thrust_kept(weak)} "
                "of its thrust, a partial failure")
    if report.verdict != "fault":
        return "a partly weakened component shows as a smaller g; none crossed a threshold"
    return "the table assumes a dead component; a weakened one gives a smaller g"


def _stays_defective(report: Report, series: Series | None) -> str:
    detected = report.detected_at_s
    if detected is None:
        return "no fault, nothing to track"
    if series is None or "b" not in series:
        return "not checked (no time histories with this report)"
    time_s, b = series["time_s"], series["b"]
    after = time_s >= detected
    alarming = np.flatnonzero(after & b.any(axis=1))
    if alarming.size == 0:
        return "not checked: no alarm sample after the detection"
    last_alarm = float(time_s[alarming[-1]])
    end = float(time_s[-1])
    if end - last_alarm > max(30.0, 0.2 * (end - detected)):
        return (f"g fell back under every threshold after {last_alarm:.1f} s and stayed "
                f"there to the end ({end:.1f} s): an intermittent fault, or one that cleared")
    return f"the alarm lasts to the end of the log ({end:.1f} s)"


def assumption_remarks(report: Report, series: Series | None) -> list[tuple[str, str]]:
    remarks = [_margin(report, series), _single_fault(report), _total_failure(report),
               _stays_defective(report, series)]
    assumptions = report.method.assumptions
    return list(zip(assumptions, remarks, strict=False))
