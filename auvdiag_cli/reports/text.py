"""The short human summary printed on the terminal."""

import math
import textwrap
from collections.abc import Sequence

from adapters import TopicInfo
from auvdiag_cli.engine.active import ActiveDiagnosis
from auvdiag_cli.engine.coverage import normal_verdict_text
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.hypotheses import HypothesisTest
from auvdiag_cli.engine.results import EPOCH_CLOCK_NS, Diagnosis, Verdict
from auvdiag_cli.engine.substitution import Substitution
from auvdiag_cli.jobs.inspect import Inspection
from auvdiag_cli.reports.json_report import utc_text

DETAIL_WIDTH = 100


def _components(names: Sequence[str]) -> str:
    return " or ".join(name.replace("_", " ") for name in names)


def summary_lines(diagnosis: Diagnosis) -> list[str]:
    d = diagnosis
    duration = d.histories.duration_s or 0.0
    lines = [f"{d.log}  ({d.format}, {duration:.1f} s, vehicle {d.vehicle})"]
    if d.completeness is not None and not d.completeness.complete:
        lines.append(f"PARTIAL LOG: analysed only what was readable: {d.completeness.reason}")
    coverage = d.coverage
    if d.verdict == Verdict.NORMAL:
        lines.append("verdict: " + normal_verdict_text(coverage.counts(), coverage.complete))
    elif d.verdict == Verdict.UNDETERMINED:
        lines.append("verdict: UNDETERMINED: no signal could be judged")
    else:
        what = (d.component.replace("_", " ") if d.component
                else _components(d.candidates) if d.candidates else "unidentified component")
        if d.degradation is not None:
            what += f" weakened to about {d.degradation.thrust_fraction:.0%} thrust"
        lines.append(f"verdict: FAULT: {what}"
                     + (f" (pattern case {d.case})" if d.case is not None else ""))
        lines.append(f"  onset    ~{d.onset_s:.1f} s   detected {d.detected_at_s:.1f} s   "
                     f"(delay {d.detected_at_s - d.onset_s:.1f} s)"
                     if d.onset_s is not None and d.detected_at_s is not None else "")
        lines.append("  b        " + ", ".join(f"{k}={v}" for k, v in d.b.items()))
        if d.hypotheses is not None:
            lines.append("  " + _hypotheses_line(d.hypotheses))
        lines += _active_lines(d.active)
        lines += _substitution_lines(d.substitution)
    lines.append(f"  coverage: {coverage.describe()}")
    lines += [f"  {name}: {why}" for name, why in d.not_judged.items()]
    check = d.command_check
    if check is not None:
        lines.append("  commands vs motion: " + (check.describe() if check.judged
                                                 else "no actuator could be judged"))
        lines += [f"    {name}: {why}" for name, why in check.not_judged.items()]
    if d.start_check is not None:
        lines.append("  start: " + d.start_check.describe(d.sensor_units))
    if d.change_check is not None:
        lines.append("  change test: " + d.change_check.describe())
    lines += effort_lines(d.effort_check)
    for result in d.segments:
        seg = result.segment
        peaks = ", ".join(f"{name} {result.max_g[name]:.1f}/{seg.thresholds[name]:g} %"
                          + (" (not judged)" if name in d.not_judged else "")
                          for name in result.max_g)
        case = f"  case {result.case}" if result.case else ""
        lines.append(f"  segment {seg.name:<8} {seg.start_s:7.1f}-{seg.end_s:7.1f} s  "
                     f"max g / threshold: {peaks}{case}")
    lines += [f"  note: {note}" for note in d.notes]
    inputs = d.model.inputs
    lines.append(f"  model: {d.model.name} ({d.model.path})"
                 + (f", driven also by the measured {', '.join(inputs)}" if inputs else ""))
    return [line for line in lines if line]


def effort_lines(check: EffortCheck | None) -> list[str]:
    """The effort line and each actuator's share against its normal band (or why not)."""
    if check is None:
        return []
    lines = ["  effort: " + check.describe()]
    shares = [f"{a.name} {a.share:.3f} ({a.normal_share:.3f} ± {a.spread:.3f}, "
              f"{a.departure:+.0%})" for a in check.actuators
              if a.share is not None and a.normal_share is not None
              and a.spread is not None and a.departure is not None]
    if shares:
        lines += textwrap.wrap("shares (normal ± spread): " + ", ".join(shares),
                               width=DETAIL_WIDTH, initial_indent="    ",
                               subsequent_indent="      ")
    reasons = dict.fromkeys(f"{a.group}: {a.not_judged}" for a in check.actuators
                            if a.not_judged is not None)
    return lines + [f"    {reason}" for reason in reasons]


def _active_lines(active: ActiveDiagnosis | None) -> list[str]:
    if active is None:
        return []
    lines: list[str] = []
    for e in active.evidence:
        verdict = "fault among" if e.faulty else "clears"
        lines.append(f"  active diagnosis: {e.segment} at {e.start_s:.1f} s "
                     f"({e.log}) tests {', '.join(e.tested)}: b = "
                     + ", ".join(str(v) for v in e.b.values())
                     + f" -> {verdict} {', '.join(e.tested)}")
    if active.recommended_dms:
        lines.append("  cannot tell these apart from this log: run "
                     + " or ".join(active.recommended_dms)
                     + " on the next dive (or give such a log with --with) to decide")
    return lines


def _substitution_lines(s: Substitution | None) -> list[str]:
    if s is None:
        return []
    lines = []
    error = (f", expected error {s.expected_error_rms:.4f} {s.unit} rms"
             if s.expected_error_rms is not None else "")
    lines.append(f"  substituting control: model {s.signal} replaces the sensor from "
                 f"{s.from_s:.1f} s{error}")
    if s.truth_error_rms is not None and s.failed_error_rms is not None:
        lines.append(f"    against the truth: substituted {s.truth_error_rms:.4f} "
                     f"{s.unit} rms, failed sensor {s.failed_error_rms:.4f} {s.unit}")
    if "truth" in s.tracks:
        lines.append("    dead-reckoned track ends "
                     f"{s.tracks['substituted'].distance_to(s.tracks['truth']):.2f} m "
                     "from the true end with the substitute, "
                     f"{s.tracks['failed'].distance_to(s.tracks['truth']):.2f} m with "
                     "the failed sensor")
    loop = s.closed_loop
    if loop is not None:
        outcome = (f"reaches its last waypoint at {loop.finished_s:.1f} s"
                   if loop.reached else "does not reach its last waypoint")
        lines.append(f"    closed-loop replay (controller fed the model from "
                     f"{loop.start_s:.1f} s): the vehicle {outcome}, ending "
                     f"{loop.miss_m:.2f} m from it")
    return lines


def _hypotheses_line(test: HypothesisTest) -> str:
    best, other, margin = test.best, test.runner_up, test.margin
    text = (f"best explained by {best.describe()} (g at most {best.peak_g_ratio:.0%} of its "
            "threshold)" if best.explains else
            f"no single-component fault explains it (closest: {best.describe()}, "
            f"{best.peak_g_ratio:.0%})")
    if other is not None and margin is not None and math.isfinite(margin):
        text += f"; runner-up {other.describe()} ({margin:.1f}x)"
    return "hypotheses: " + text


def _utc(time_ns: int | None) -> str:
    if time_ns is None:
        return "?"
    if time_ns <= EPOCH_CLOCK_NS:  # since boot, or since whatever the log counts from
        return f"{time_ns / 1e9:.3f} s (the log's clock, not a date)"
    return utc_text(time_ns, "milliseconds") or f"{time_ns} ns (not a date)"


def _wrapped(label: str, items: list[str]) -> list[str]:
    return textwrap.wrap(", ".join(items), width=DETAIL_WIDTH,
                         initial_indent=f"      {label:<10}", subsequent_indent=" " * 16)


def _topic_details(topic: TopicInfo) -> list[str]:
    """What a profile can name on this topic: fields, instance values, NAMED_VALUE names."""
    lines = _wrapped("fields", list(topic.fields)) if topic.fields else []
    for key, values in topic.instances:
        choose = f" (several: choose with where = {{ {key} = {values[0]} }})" \
            if len(values) > 1 else ""
        lines += _wrapped("instances", [f"{key} = {', '.join(values)}{choose}"])
    if topic.names:
        lines += _wrapped("names", [f'{", ".join(topic.names)} (where = {{ name = "…" }})'])
    return lines


def _while_logged(count: int, rate_hz: float | None, duration_s: float | None) -> str:
    """The rate between a signal's samples (the median interval), and how much of the log
    that covers when it is logged in bursts (the table's mean rate is over the whole log)."""
    if not rate_hz:
        return ""
    text = f", {rate_hz:.1f} Hz between samples"
    covered_s = count / rate_hz
    if duration_s and covered_s < 0.8 * duration_s:
        text += f": about {covered_s:.0f} s of the log's {duration_s:.0f} s"
    return text


def inspection_lines(inspection: Inspection) -> list[str]:
    inv = inspection.inventory
    duration = inv.duration_s
    lines = [f"{inspection.path}", f"  format    {inv.format} (profile mapping: "
             f"[sources.{inspection.family}])",
             f"  span      {_utc(inv.start_ns)} … {_utc(inv.end_ns)}"
             + (f"  ({duration:.1f} s)" if duration is not None else "")]
    lines.append(f"  {'topic / message':<32} {'type':<34} {'count':>8} {'mean rate':>9}")
    for topic in inv.topics:
        rate = f"{topic.count / duration:.1f} Hz" if duration else ""
        lines.append(f"  {topic.name:<32} {topic.type:<34} {topic.count:>8} {rate:>9}")
        lines += _topic_details(topic)
    if not inspection.checked:
        lines.append("  profile signals: not checked (add --profile to see which resolve)")
    elif not inspection.mapped:
        lines.append(f"  profile signals: none to look for: the profile has no "
                     f"[sources.{inspection.family}] mapping for {inv.format} logs")
    else:
        lines.append("  profile signals:")
    for s in inspection.signals:
        where = f"{s.topic} {s.field}"
        if s.resolved:
            lines.append(f"    ok       {s.name:<12} {where}  ({s.count} samples"
                         f"{_while_logged(s.count, s.rate_hz, duration)}; {s.on_grid})")
        else:
            hint = f"; closest: {', '.join(s.candidates)}" if s.candidates else ""
            lines.append(f"    MISSING  {s.name:<12} {where}  ({s.problem}{hint})")
    if inspection.markers:
        lines.append(f"  segment markers: {' '.join(inspection.markers)}")
    lines += [f"  warning: {warning}" for warning in inspection.warnings]
    lines += [f"  note: {note}" for note in inv.notes]
    return lines
