"""The short human summary printed on the terminal."""

import textwrap

from adapters import TopicInfo
from auvdiag_cli.engine.autopilot_words import said_in
from auvdiag_cli.engine.results import EPOCH_CLOCK_NS
from auvdiag_cli.jobs.inspect import Inspection
from auvdiag_cli.reports.json_report import utc_text, verdict_title
from auvdiag_cli.reports.report import ActivePart, ActuatorsPart, Report
from auvdiag_cli.reports.sentences import (
    by_reason,
    give_or_take,
    hypotheses_sentence,
    names,
    onset_may_be_earlier,
    substitution_facts,
    thrust_kept,
)

DETAIL_WIDTH = 100


def summary_lines(report: Report) -> list[str]:
    """The terminal summary of a diagnosis."""
    r, coverage = report, report.coverage
    lines = [f"{r.log}  ({r.format}, {r.duration_s or 0.0:.1f} s, vehicle {r.vehicle})"]
    if r.partial and r.completeness is not None:
        lines.append(f"PARTIAL LOG: analysed only what was readable: {r.completeness.reason}")
    if r.verdict == "fault":
        lines += _fault_lines(r)
    else:
        lines.append("verdict: " + verdict_title(r))
    if r.autopilot is not None:
        lines.append(f"  autopilot: {r.autopilot.summary}")
    if coverage is not None:
        lines.append(f"  coverage: {coverage.engine().describe()}")
    lines += [f"  {who}: {why}" for who, why in by_reason(r.not_judged)]
    if r.commands_check is not None:
        lines.append("  commands vs motion: " + r.commands_check.summary)
        lines += [f"    {who}: {why}" for who, why in by_reason(r.commands_check.not_judged)]
    if r.start_check is not None:
        lines.append("  start: " + r.start_check.summary)
    if r.change_check is not None:
        lines.append("  change test: " + r.change_check.summary)
    lines += effort_lines(r.actuators)
    for segment in r.segments:
        peaks = ", ".join(f"{name} {_percent(g)}/{segment.thresholds.get(name, 0):.4g} %"
                          + (" (not judged)" if name in r.not_judged else "")
                          for name, g in segment.max_g.items())
        if all(name in r.not_judged for name in segment.max_g):
            peaks = "none judged by the replay"
        case = f"  case {segment.case}" if segment.case else ""
        lines.append(f"  segment {segment.name:<8} {segment.start_s:7.1f}-"
                     f"{segment.end_s:7.1f} s  max g / threshold: {peaks}{case}")
    lines += [f"  note: {note}" for note in r.notes]
    inputs = r.model.inputs
    lines.append(f"  model: {r.model.name} ({r.model.path})"
                 + (f", driven also by the measured {', '.join(inputs)}" if inputs else ""))
    return [line for line in lines if line]


def _percent(g: float | None) -> str:
    return "-" if g is None else f"{g:.1f}"


def _fault_lines(r: Report) -> list[str]:
    what = r.component.replace("_", " ") if r.component else (
        names(r.candidates) or "unidentified component")
    if r.degradation is not None:
        what += f" weakened to {thrust_kept(r.degradation)} thrust"
    lines = [f"verdict: FAULT: {what}" + (f" (pattern case {r.case})" if r.case is not None
                                         else "")]
    if r.onset_s is not None and r.detected_at_s is not None:
        earlier = onset_may_be_earlier(r)
        lines.append(f"  onset    ~{r.onset_s:.1f} s{' or earlier' if earlier else ''}"
                     f"{give_or_take(r.onset_error_s)}   "
                     f"detected {r.detected_at_s:.1f} s   "
                     f"(delay {r.detected_at_s - r.onset_s:.1f} s{' or more' if earlier else ''})")
    lines.append("  b        " + ", ".join(f"{k}={v}" for k, v in r.b.items()))
    if r.hypotheses is not None:
        lines.append("  hypotheses: " + hypotheses_sentence(r.hypotheses))
    lines += _active_lines(r.active_diagnosis)
    if r.substitution is not None:
        (_, first), *rest = substitution_facts(r.substitution)
        lines.append(f"  substituting control: {first}")
        lines += [f"    {label.lower()}: {text}" for label, text in rest]
    return lines


def effort_lines(check: ActuatorsPart | None) -> list[str]:
    """The effort line and each actuator's share against its normal band (or why not)."""
    if check is None:
        return []
    lines = ["  effort: " + check.summary]
    shares = [f"{name} {a.share:.3f} ({a.normal_share:.3f} ± {a.spread:.3f}, "
              f"{a.departure:+.0%})" for name, a in check.shares.items()
              if a.share is not None and a.normal_share is not None
              and a.spread is not None and a.departure is not None]
    if shares:
        lines += textwrap.wrap("shares (normal ± spread): " + ", ".join(shares),
                               width=DETAIL_WIDTH, initial_indent="    ",
                               subsequent_indent="      ")
    reasons = dict.fromkeys(f"{a.group}: {a.not_judged}" for a in check.shares.values()
                            if a.not_judged is not None)
    return lines + [f"    {reason}" for reason in reasons]


def _active_lines(active: ActivePart | None) -> list[str]:
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


def _span(start_ns: int | None, end_ns: int | None) -> str:
    """A log's first and last time: dates where its clock is UTC, else seconds on its own
    clock (since boot, or since whatever the log counts from), said once."""
    if start_ns is None or end_ns is None:
        return "? … ?"
    if end_ns <= EPOCH_CLOCK_NS:
        return f"{start_ns / 1e9:.3f} … {end_ns / 1e9:.3f} s on the log's clock (not a date)"
    return " … ".join(utc_text(t, "milliseconds") or f"{t} ns (not a date)"
                      for t in (start_ns, end_ns))


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
             f"  span      {_span(inv.start_ns, inv.end_ns)}"
             + (f"  ({duration:.1f} s)" if duration is not None else "")]
    setup = inspection.autopilot
    if setup is not None:
        lines.append(f"  vehicle   {setup.vehicle or 'not said'} ({setup.evidence})")
    said = said_in(inv.autopilot_messages, inv.start_ns or 0)
    if said is not None:
        lines.append("  autopilot " + (f"reported trouble: {said.quoted()}" if said.alarms
                                       else f"no warning or error ({said.other_messages} "
                                       "message(s))") + said.standing_text())
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
            held = (": a measured input, held at its typical value on normal logs"
                    if s.optional else "")
            lines.append(f"    {'absent' if s.optional else 'MISSING':<8} {s.name:<12} {where}  "
                         f"({s.problem}{held}{hint})")
    if inspection.markers:
        lines.append(f"  segment markers: {' '.join(inspection.markers)}")
    lines += [f"  warning: {warning}" for warning in inspection.warnings]
    lines += [f"  note: {note}" for note in inv.notes]
    return lines
