"""The machine-readable report (SPEC §5): a plain dict, written as JSON."""

import math
from datetime import UTC, datetime
from typing import Any

from auvdiag_cli import __version__
from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.closed_loop import ClosedLoopReplay
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.coverage import normal_verdict_text
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.hypotheses import Hypothesis
from auvdiag_cli.engine.results import (
    EPOCH_CLOCK_NS,
    PAPER_ASSUMPTIONS,
    Diagnosis,
    SegmentResult,
)
from auvdiag_cli.engine.substitution import Substitution

SCHEMA_VERSION = 1


def _finite(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else value


def diagnosis_to_dict(diagnosis: Diagnosis) -> dict[str, Any]:
    return {
        "schema_version": SCHEMA_VERSION,
        "tool": f"auvdiag {__version__}",
        "log": str(diagnosis.log),
        "format": diagnosis.format,
        "vehicle": diagnosis.vehicle,
        "verdict": diagnosis.verdict.value,
        "component": diagnosis.component,
        "candidates": diagnosis.candidates,
        "case": diagnosis.case,
        "b": diagnosis.b,
        "units": diagnosis.sensor_units,
        "detected_at_s": diagnosis.detected_at_s,
        "onset_s": diagnosis.onset_s,
        "duration_s": _seconds(diagnosis.histories.duration_s),
        "start_time_utc": utc_text(diagnosis.start_ns, "milliseconds"),
        "onset_utc": _utc_after(diagnosis.start_ns, diagnosis.onset_s),
        "detected_at_utc": _utc_after(diagnosis.start_ns, diagnosis.detected_at_s),
        "completeness": None if diagnosis.completeness is None
        else diagnosis.completeness.to_dict(),
        "not_operating_s": diagnosis.not_operating_s,
        "not_judged": diagnosis.not_judged,
        "coverage": diagnosis.coverage.to_dict(),
        "segments": [_segment(r) for r in diagnosis.segments],
        "segment_source": diagnosis.segment_source,
        "degradation": None if diagnosis.degradation is None else {
            "component": diagnosis.degradation.component, "kind": "weakened",
            "thrust_fraction": diagnosis.degradation.thrust_fraction,
            "peak_g_over_threshold": diagnosis.degradation.peak_g_ratio},
        "hypotheses": _hypotheses(diagnosis),
        "commands_check": _command_check(diagnosis.command_check),
        "start_check": _start_check(diagnosis),
        "change_check": _change_check(diagnosis.change_check),
        "actuators": _actuators(diagnosis.effort_check),
        "active_diagnosis": _active(diagnosis),
        "substitution": _substitution(diagnosis.substitution),
        "model": diagnosis.model.as_dict(),
        "method": {
            "g": "g_i(k) = 100/(K R_i) * sum_{j=k-K+1..k} |SS_i(j) - SM_i(j)| (mean of K samples)",
            "window_samples": diagnosis.window_samples,
            "decision_window_s": diagnosis.decision_window_s,
            "assumptions": list(PAPER_ASSUMPTIONS),
        },
        "notes": diagnosis.notes,
    }


def verdict_title(document: dict[str, Any]) -> str:
    """The verdict in words, from a report: the component a fault names, and how much a
    NORMAL covered when it did not cover everything."""
    verdict = str(document["verdict"])
    if verdict == "normal":
        coverage = document.get("coverage") or {}
        return normal_verdict_text(coverage.get("summary"), coverage.get("complete", True))
    if verdict == "fault":
        named = named_components(document).replace("_", " ")
        return f"FAULT: {named or 'component not identified'}"
    return verdict.upper()


def named_components(document: dict[str, Any]) -> str:
    """What a report blames, in words: its component, or its candidates joined by "or"
    ("" when it names none)."""
    return str(document.get("component") or " or ".join(document.get("candidates") or []))


def _seconds(value: float | None) -> float | None:
    return None if value is None else round(value, 3)


def _segment(r: SegmentResult) -> dict[str, Any]:
    return {"name": r.segment.name, "start_s": round(r.segment.start_s, 3),
            "end_s": round(r.segment.end_s, 3), "mode": r.segment.mode,
            "thresholds": r.segment.thresholds,
            "max_g": {k: _finite(v) for k, v in r.max_g.items()}, "b": r.b, "case": r.case,
            "components": list(r.components)}


def _substitution(substitution: Substitution | None) -> dict[str, Any] | None:
    if substitution is None:
        return None
    tracks = substitution.tracks
    return {
        "signal": substitution.signal,
        "from_s": substitution.from_s,
        "unit": substitution.unit,
        "expected_error_rms": substitution.expected_error_rms,
        "truth_error_rms": _rounded(substitution.truth_error_rms),
        "failed_sensor_error_rms": _rounded(substitution.failed_error_rms),
        "track_end_m": {name: [round(v, 3) for v in track.end] for name, track in tracks.items()},
        "track_end_error_m": {name: round(track.distance_to(tracks["truth"]), 3)
                              for name, track in tracks.items()
                              if name != "truth" and "truth" in tracks},
        "closed_loop": _closed_loop(substitution.closed_loop),
    }


def utc_text(time_ns: int, timespec: str = "seconds") -> str | None:
    """A time as UTC, when its clock is Unix time (not time since boot) and a date at all."""
    if time_ns <= EPOCH_CLOCK_NS:
        return None
    try:
        return datetime.fromtimestamp(time_ns / 1e9, UTC).isoformat(timespec=timespec)
    except (OverflowError, ValueError, OSError):  # a damaged clock is no date
        return None


def _utc_after(start_ns: int, seconds: float | None) -> str | None:
    """A report time as UTC to the millisecond, where the log's clock is Unix time."""
    return None if seconds is None else utc_text(start_ns + round(seconds * 1e9),
                                                 "milliseconds")


def _closed_loop(replay: ClosedLoopReplay | None) -> dict[str, Any] | None:
    if replay is None:
        return None
    return {"from_s": replay.start_s, "reached_last_waypoint": replay.reached,
            "finished_s": replay.finished_s, "miss_m": replay.miss_m,
            "last_waypoint_m": list(replay.last_waypoint),
            "end_m": [round(float(replay.x_m[-1]), 3), round(float(replay.y_m[-1]), 3)]}


def _rounded(value: float | None) -> float | None:
    return None if value is None else round(value, 5)


def _hypothesis(h: Hypothesis | None) -> dict[str, Any] | None:
    return None if h is None else {"component": h.component, "kind": h.kind,
                                   "description": h.describe(),
                                   "thrust_fraction": h.thrust_fraction,
                                   "stuck_at": h.stuck_at,
                                   "peak_g_over_threshold": _finite(h.peak_g_ratio),
                                   "explains": h.explains}


def _hypotheses(diagnosis: Diagnosis) -> dict[str, Any] | None:
    """The hypothesis test's verdict: the best, the runner-up (another component), the
    margin between them, and whether the pattern table's candidates include the best."""
    test = diagnosis.hypotheses
    if test is None:
        return None
    return {"best": _hypothesis(test.best), "runner_up": _hypothesis(test.runner_up),
            "margin": _finite(_rounded(test.margin)),
            "table_agrees": (test.best.component in diagnosis.candidates
                             if diagnosis.case is not None else None),
            "ranked": [_hypothesis(h) for h in test.ranked]}


def _command_check(check: CommandCheck | None) -> dict[str, Any] | None:
    if check is None:
        return None
    return {"summary": check.describe() if check.judged else "no actuator could be judged",
            "window_s": check.window_s, "extra_effort_allowed": check.thresholds,
            "peak_over_threshold": check.peak_ratio, "not_judged": check.not_judged,
            "alarm_s": check.alarm_s, "onset_s": check.onset_s, "named": list(check.named),
            "explained": check.explained,
            "extra_effort": check.extra_effort}


def _change_check(check: ChangeCheck | None) -> dict[str, Any] | None:
    """The log against its own beginning (null: the model has no change thresholds)."""
    if check is None:
        return None
    return {"summary": check.describe(), "judged": check.judged,
            "judged_from_s": check.judged_from_s,
            "thresholds": {s: dict(v) for s, v in check.thresholds.items()},
            "peaks": {s: dict(v) for s, v in check.peaks.items()},
            "alarm_s": check.alarm_s, "onset_s": check.onset_s,
            "onset_error_s": check.onset_error_s, "flagged": dict(check.flagged)}


def _actuators(check: EffortCheck | None) -> dict[str, Any] | None:
    """Each actuator's share of its group's effort against normal logs (null: the model has
    no effort model)."""
    if check is None:
        return None
    return {"summary": check.describe(), "judged": check.judged,
            "false_alarm_rate": check.false_alarm_rate, "alarm_s": check.alarm_s,
            "onset_s": check.onset_s, "named": list(check.named),
            "signatures": [{"actuator": n, "match": m} for n, m in check.matches],
            "shares": {a.name: {"group": a.group, "component": a.component, "share": a.share,
                                "normal_share": a.normal_share, "spread": a.spread,
                                "departure": a.departure, "over_threshold": a.ratio,
                                "driven_harder": a.driven_harder,
                                "judged": a.not_judged is None, "not_judged": a.not_judged}
                       for a in check.actuators}}


def _start_check(diagnosis: Diagnosis) -> dict[str, Any] | None:
    start = diagnosis.start_check
    if start is None:
        return None
    return {"summary": start.describe(diagnosis.sensor_units), "judged": start.judged,
            "deviation": start.deviation, "allowed": start.thresholds, "off": list(start.off),
            "at_s": start.at_s}


def _active(diagnosis: Diagnosis) -> dict[str, Any] | None:
    active = diagnosis.active
    if active is None:
        return None
    return {
        "candidates_before": active.candidates_before,
        "candidates_after": active.candidates,
        "evidence": [{"log": e.log, "segment": e.segment, "start_s": e.start_s, "b": e.b,
                      "tested": list(e.tested), "faulty": e.faulty} for e in active.evidence],
        "recommended_dms": active.recommended_dms,
        "conflict": active.conflict,
    }
