"""What the first page of a dive report says, in words, from the JSON report."""

from typing import Any

import numpy as np

from auvdiag_cli.reports.series import Series


def _names(components: list[str]) -> str:
    return " or ".join(c.replace("_", " ") for c in components)


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} s"


def _when(document: dict[str, Any]) -> str:
    onset, detected = document.get("onset_s"), document.get("detected_at_s")
    if detected is None:
        return "no alarm"
    delay = "" if onset is None else f" (delay {detected - onset:.1f} s)"
    return f"onset about {_seconds(onset)}, detected at {_seconds(detected)}{delay}"


def _model(document: dict[str, Any]) -> str:
    model = document.get("model") or {}
    text = f"{model.get('name')} for {model.get('vehicle')}, created {model.get('created')}"
    errors = model.get("heldout_error_rms")
    units = document.get("units", {})
    if errors:
        text += "; held-out error " + ", ".join(
            f"{k} {v:.4f} {units.get(k, '')}".rstrip() for k, v in errors.items())
    if model.get("inputs"):
        text += "; driven by the commands and the measured " + ", ".join(model["inputs"])
    horizon = model.get("horizon_s")
    text += ("; free-running replay" if horizon is None
             else f"; replay re-started every {horizon:g} s")
    calibrated, budget = model.get("thresholds_calibrated"), model.get("false_alarm_rate")
    text += (f"; thresholds set for {budget['rate']:g} false alarms per {budget['per']}" if budget
             else "; thresholds calibrated on normal logs" if calibrated
             else "; thresholds: the profile's (the paper's for the Twin-Burger)")
    return text


def _substitution(s: dict[str, Any]) -> list[tuple[str, str]]:
    facts = [("Substituting Control", f"the model's {s['signal']} replaces the sensor from "
              f"{_seconds(s['from_s'])}" + ("" if s.get("expected_error_rms") is None else
                                            f", expected error {s['expected_error_rms']:.4f} "
                                            f"{s['unit']} rms"))]
    if s.get("truth_error_rms") is not None:
        facts.append(("Against the truth", f"substitute {s['truth_error_rms']:.4f} {s['unit']} "
                      f"rms, failed sensor {s['failed_sensor_error_rms']:.4f} {s['unit']} rms"))
    ends = s.get("track_end_error_m") or {}
    if ends:
        facts.append(("Dead-reckoned end", ", ".join(f"{k} {v:.2f} m from the truth"
                                                     for k, v in ends.items())))
    loop = s.get("closed_loop")
    if loop:
        outcome = (f"reaches the last waypoint at {_seconds(loop['finished_s'])}" if
                   loop["reached_last_waypoint"] else "does not reach the last waypoint")
        facts.append(("Closed-loop replay", f"fed the model from {_seconds(loop['from_s'])}, "
                      f"the controller {outcome}, ending {loop['miss_m']:.2f} m from it"))
    return facts


def _hypothesis(h: dict[str, Any]) -> str:
    described = h.get("description")      # reports saved before it: rebuilt from the kind
    if described is None:
        kind = (f"weakened to {h['thrust_fraction']:.0%} thrust" if h["kind"] == "weakened"
                else h["kind"])
        described = f"{h['component'].replace('_', ' ')} {kind}"
    ratio = h.get("peak_g_over_threshold")
    return described + ("" if ratio is None else f" ({ratio:.0%} of threshold)")


def _hypotheses(test: dict[str, Any]) -> str:
    best, other = test["best"], test.get("runner_up")
    text = ("best explained by " if best["explains"] else
            "no single-component fault explains it; closest: ") + _hypothesis(best)
    if other is not None:
        text += "; runner-up " + _hypothesis(other)
    return text


def summary_facts(document: dict[str, Any]) -> list[tuple[str, str]]:
    """(label, value) pairs, most important first."""
    duration = document.get("duration_s")
    facts = [("Log", f"{document['log']} ({document['format']}, "
              f"{_seconds(duration)}, vehicle {document['vehicle']})")]
    if document["verdict"] == "fault":
        if document.get("component"):
            facts.append(("Component", document["component"].replace("_", " ")))
        else:
            facts.append(("Candidates", _names(document.get("candidates") or [])
                          or "none: b fits no row of the pattern table"))
        facts.append(("When", _when(document)))
    b = " ".join(f"{k}={v}" for k, v in document.get("b", {}).items())
    case = document.get("case")
    facts.append(("Pattern table", f"case {case}, b = {b}" if case is not None
                  else f"b = {b} fits no row"))
    hypotheses = document.get("hypotheses")
    if hypotheses:
        facts.append(("Hypotheses", _hypotheses(hypotheses)))
    coverage = document.get("coverage")
    if coverage:
        facts.append(("Judged", coverage["summary"]))
    not_judged = document.get("not_judged") or {}
    if not_judged:
        facts.append(("Not judged", "; ".join(f"{k}: {v}" for k, v in not_judged.items())))
    commands = document.get("commands_check")
    if commands:
        facts.append(("Commands vs motion", commands["summary"]))
    actuators = document.get("actuators")
    if actuators and actuators.get("judged"):
        facts.append(("Effort shares", actuators["summary"]))
    start = document.get("start_check")
    if start and start.get("judged"):
        facts.append(("Start", start["summary"]))
    change = document.get("change_check")
    if change:
        facts.append(("Against its beginning", change["summary"]))
    weak = document.get("degradation")
    if weak:
        facts.append(("Partial failure", f"{weak['component'].replace('_', ' ')} gives about "
                      f"{weak['thrust_fraction']:.0%} of its thrust"))
    active = document.get("active_diagnosis")
    if active and active.get("recommended_dms"):
        facts.append(("Next dive", "run " + " or ".join(active["recommended_dms"])
                      + " to tell the candidates apart"))
    if document.get("substitution"):
        facts += _substitution(document["substitution"])
    routine = sum(1 for s in document.get("segments", []) if s["mode"] == "routine")
    facts.append(("Segments", f"{len(document.get('segments', []))} ({routine} Diagnosis "
                  f"Motion Sequences), from the log's {document.get('segment_source')}"))
    facts.append(("Model", _model(document)))
    return facts


def _margin(document: dict[str, Any], series: Series | None) -> str:
    """How close the healthy stretch of the log came to an alarm."""
    caveat = "; currents, a tether or a changed payload would raise g like a fault"
    if series is None or "g_percent" not in series:
        return "not checked (no time histories with this report)"
    time_s, names = series["time_s"], [str(n) for n in series["sensor_names"]]
    onset = document.get("onset_s")
    healthy = time_s < onset if onset is not None else np.ones(time_s.shape, bool)
    judged = np.array([name not in (document.get("not_judged") or {}) for name in names])
    if not judged.any():
        return "no signal is judged"
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = series["g_percent"][healthy] / series["thresholds"][healthy]
    ratio[:, ~judged] = np.nan          # an unjudged signal's g is no margin to an alarm
    if not np.isfinite(ratio).any():
        return "no healthy stretch long enough to judge before the onset"
    row, column = np.unravel_index(np.nanargmax(ratio), ratio.shape)
    where = "before the onset" if onset is not None else "in the whole log"
    return (f"{where}, g peaked at {ratio[row, column]:.0%} of its threshold ({names[column]} "
            f"at {time_s[healthy][row]:.1f} s){caveat}")


def _single_fault(document: dict[str, Any]) -> str:
    if document["verdict"] != "fault":
        return "nothing was found to fail"
    if document.get("case") is None:
        return ("b fits no row of the pattern table: more than one fault, or one the table "
                "does not describe; the verdict names no component")
    return f"b fits case {document['case']} of the table; two faults at once could mimic it"


def _total_failure(document: dict[str, Any]) -> str:
    weak = document.get("degradation")
    if weak:
        return (f"not so here: {weak['component'].replace('_', ' ')} kept about "
                f"{weak['thrust_fraction']:.0%} of its thrust, a partial failure")
    if document["verdict"] != "fault":
        return "a partly weakened component shows as a smaller g; none crossed a threshold"
    return "the table assumes a dead component; a weakened one gives a smaller g"


def _stays_defective(document: dict[str, Any], series: Series | None) -> str:
    detected = document.get("detected_at_s")
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


def assumption_remarks(document: dict[str, Any], series: Series | None
                       ) -> list[tuple[str, str]]:
    assumptions = document.get("method", {}).get("assumptions", [])
    remarks = [_margin(document, series), _single_fault(document), _total_failure(document),
               _stays_defective(document, series)]
    return list(zip(assumptions, remarks, strict=False))
