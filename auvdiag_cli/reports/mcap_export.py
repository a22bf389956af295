"""The diagnosis as an MCAP file, to open beside the original log in Foxglove or PlotJuggler.

Drawn, like the PDF, from the report (`reports.report.Report`) and its time histories only,
on the log's own clock (every time is the log's first message plus the report's seconds).
Messages are JSON with a JSON schema, which both viewers plot without plugins. Topics (see
docs/reports.md):

- ``/auvdiag/signals/NAME``: per judged quantity, each model step: ``sensor`` (SS),
  ``model`` (SM), ``g_percent``, ``threshold_percent``, ``b`` (0/1), and ``substituted``
  where Substituting Control replaced the sensor;
- ``/auvdiag/commands``: the actuator commands, each model step;
- ``/auvdiag/change``: where the change test ran, each signal and signature it judges, its
  statistic over its threshold (1: the threshold; null while its reference fills), each
  model step;
- ``/auvdiag/effort/GROUP``: each actuator's share of its group's effort, window by window,
  and the normal share for the window's conditions (``NAME`` and ``NAME_normal``);
- ``/auvdiag/segments``: one message at the start of each segment (DMS run or mission);
- ``/auvdiag/events``: onset, detection and the verdict, as ``foxglove.Log`` messages (the
  Log panel lists them);
- ``/auvdiag/verdict``: the verdict once, at the detection (or at the log's end).
"""

import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from auvdiag_cli import __version__
from auvdiag_cli.reports.json_report import verdict_title
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.series import Series
from auvdiag_errors import UsageError

TOPIC_PREFIX = "/auvdiag"
SIGNAL_FIELDS = ("sensor", "model", "g_percent", "threshold_percent", "b", "substituted")

LOG_LEVEL_INFO, LOG_LEVEL_WARNING = 2, 3    # foxglove.Log levels

_NUMBER = {"type": ["number", "null"]}
_TIME = {"type": "object", "properties": {"sec": {"type": "integer"},
                                          "nsec": {"type": "integer"}}}
SCHEMAS: dict[str, dict[str, Any]] = {
    "auvdiag.Signal": {"type": "object", "properties": {name: _NUMBER
                                                        for name in SIGNAL_FIELDS}},
    "auvdiag.Segment": {"type": "object", "properties": {
        "name": {"type": "string"}, "mode": {"type": "string"}, "start_s": _NUMBER,
        "end_s": _NUMBER, "thresholds": {"type": "object"}, "max_g": {"type": "object"},
        "case": {"type": ["integer", "null"]}}},
    "auvdiag.Verdict": {"type": "object", "properties": {
        "verdict": {"type": "string"}, "component": {"type": ["string", "null"]},
        "candidates": {"type": "array", "items": {"type": "string"}},
        "case": {"type": ["integer", "null"]}, "onset_s": _NUMBER, "detected_at_s": _NUMBER,
        "summary": {"type": "string"}}},
    # Foxglove's own log message: its Log panel shows these without configuration.
    "foxglove.Log": {"type": "object", "properties": {
        "timestamp": _TIME, "level": {"type": "integer"}, "message": {"type": "string"},
        "name": {"type": "string"}, "file": {"type": "string"}, "line": {"type": "integer"}}},
}


def _number(value: Any) -> float | None:
    """A plain JSON number: the float32 histories' 7 significant digits, not their binary
    expansion (0.001, not 0.0010000000474974513); null where there is no value."""
    number = float(value)
    return float(f"{number:.7g}") if math.isfinite(number) else None


def _numbers_schema(names: list[str]) -> dict[str, Any]:
    return {"type": "object", "properties": {name: _NUMBER for name in names}}


class _Channels:
    """Registers a topic's schema and channel the first time it is written to."""

    def __init__(self, writer: Any) -> None:
        self.writer = writer
        self.schemas: dict[str, int] = {}
        self.channels: dict[str, int] = {}
        self.sequence = 0

    def write(self, topic: str, schema: str, body: dict[str, Any], time_ns: int,
              schema_text: dict[str, Any] | None = None) -> None:
        if topic not in self.channels:
            if schema not in self.schemas:
                data = json.dumps(schema_text or SCHEMAS[schema]).encode()
                self.schemas[schema] = self.writer.register_schema(schema, "jsonschema", data)
            self.channels[topic] = self.writer.register_channel(topic, "json",
                                                                self.schemas[schema])
        self.sequence += 1
        self.writer.add_message(self.channels[topic], log_time=time_ns, publish_time=time_ns,
                                data=json.dumps(body).encode(), sequence=self.sequence)


def _stamp(time_ns: int) -> dict[str, int]:
    return {"sec": time_ns // 1_000_000_000, "nsec": time_ns % 1_000_000_000}


def _events(report: Report) -> Iterator[tuple[float, int, str]]:
    """(seconds, level, text) of what happened when, in time order."""
    found: list[tuple[float, int, str]] = []
    if report.onset_s is not None:
        found.append((report.onset_s, LOG_LEVEL_WARNING,
                      "fault onset (estimated): the residual starts to grow"))
    if report.detected_at_s is not None:
        found.append((report.detected_at_s, LOG_LEVEL_WARNING,
                      f"fault detected: {report.named or 'component not identified'}"))
    if report.autopilot is not None:
        found += [(a.first_s, LOG_LEVEL_WARNING, f"the autopilot said: {a.text}"
                   + (f" ({a.times} times to {a.last_s:.1f} s)" if a.times > 1 else ""))
                  for a in report.autopilot.alarms]
    yield from sorted(found)


def write_diagnosis_mcap(report: Report, series: Series, target: Path) -> None:
    """Write the diagnosis at ``target`` (atomically: a viewer never opens half a file)."""
    from mcap.writer import Writer

    start_ns = int(series["start_ns"]) if "start_ns" in series else 0
    times_ns = start_ns + np.round(series["time_s"] * 1e9).astype(np.int64)
    temporary = target.with_name(f".{target.name}.tmp")
    try:
        with temporary.open("wb") as stream:
            writer = Writer(stream)
            writer.start(profile="", library=f"auvdiag {__version__}")
            channels = _Channels(writer)
            _write_time_histories(channels, report, series, times_ns)
            _write_segments(channels, report, start_ns)
            _write_effort(channels, series, start_ns)
            _write_events(channels, report, start_ns, int(times_ns[-1]) if times_ns.size
                          else start_ns)
            coverage = None if report.coverage is None else report.coverage.summary
            writer.add_metadata("auvdiag", {
                "log": report.log, "format": report.format, "vehicle": report.vehicle,
                "verdict": verdict_title(report), "coverage": str(coverage),
                "model": str(report.model.name), "log_start_ns": str(start_ns)})
            writer.finish()
        temporary.replace(target)
    except OSError as error:
        temporary.unlink(missing_ok=True)
        raise UsageError(f"{target}: cannot write the MCAP: {error.strerror or error}"
                         ) from None


def _write_time_histories(channels: _Channels, report: Report, series: Series,
                          times_ns: np.ndarray) -> None:
    """The model-step messages, interleaved in time order as MCAP readers prefer."""
    names = [str(n) for n in series["sensor_names"]]
    commands = [str(n) for n in series["command_names"]]
    substituted = series.get("substituted")
    replaced = (report.substitution.signal
                if substituted is not None and report.substitution is not None else None)
    columns = {"sensor": series.get("measured"), "model": series.get("modelled"),
               "g_percent": series.get("g_percent"), "threshold_percent": series["thresholds"],
               "b": series["b"]}
    present = {key: values for key, values in columns.items()
               if values is not None and values.shape == (times_ns.size, len(names))}
    commands_schema = _numbers_schema(commands)
    change = series.get("change_ratio")
    judged = [str(n) for n in series.get("change_names", [])]
    change_schema = _numbers_schema(judged)
    for step, time_ns in enumerate(times_ns.tolist()):
        for column, name in enumerate(names):
            body = {key: _number(values[step, column]) for key, values in present.items()}
            if "b" in body and body["b"] is not None:
                body["b"] = int(body["b"])
            if name == replaced and substituted is not None:
                body["substituted"] = _number(substituted[step])
            channels.write(f"{TOPIC_PREFIX}/signals/{name}", "auvdiag.Signal", body, time_ns)
        if commands:
            channels.write(f"{TOPIC_PREFIX}/commands", "auvdiag.Commands",
                           _row(series["commands"], commands, step), time_ns, commands_schema)
        if change is not None and judged:
            channels.write(f"{TOPIC_PREFIX}/change", "auvdiag.ChangeOverThreshold",
                           _row(change, judged, step), time_ns, change_schema)


def _row(values: np.ndarray, names: list[str], step: int) -> dict[str, float | None]:
    """One step of a table of histories, by column name."""
    return {name: _number(values[step, k]) for k, name in enumerate(names)}


def _write_effort(channels: _Channels, series: Series, start_ns: int) -> None:
    for k, group in enumerate(str(g) for g in series.get("effort_groups", [])):
        members = [str(m) for m in series[f"effort_{k}_members"]]
        fields = [name for m in members for name in (m, f"{m}_normal")]
        schema = _numbers_schema(fields)
        shares, normal = series[f"effort_{k}_shares"], series[f"effort_{k}_normal"]
        for row, seconds in enumerate(series[f"effort_{k}_time_s"].tolist()):
            body: dict[str, float | None] = {}
            for i, member in enumerate(members):
                body[member] = _number(shares[row, i])
                body[f"{member}_normal"] = _number(normal[row, i])
            channels.write(f"{TOPIC_PREFIX}/effort/{group}", "auvdiag.EffortShares", body,
                           start_ns + round(seconds * 1e9), schema)


def _write_segments(channels: _Channels, report: Report, start_ns: int) -> None:
    for segment in report.segments:
        body = {"name": segment.name, "mode": segment.mode, "start_s": segment.start_s,
                "end_s": segment.end_s, "thresholds": dict(segment.thresholds),
                "max_g": dict(segment.max_g), "case": segment.case}
        channels.write(f"{TOPIC_PREFIX}/segments", "auvdiag.Segment", body,
                       start_ns + round(float(segment.start_s) * 1e9))


def _write_events(channels: _Channels, report: Report, start_ns: int, end_ns: int) -> None:
    for seconds, level, text in _events(report):
        time_ns = start_ns + round(float(seconds) * 1e9)
        channels.write(f"{TOPIC_PREFIX}/events", "foxglove.Log",
                       {"timestamp": _stamp(time_ns), "level": level, "message": text,
                        "name": "auvdiag", "file": "", "line": 0}, time_ns)
    detected = report.detected_at_s
    verdict_ns = end_ns if detected is None else start_ns + round(float(detected) * 1e9)
    summary = verdict_title(report)
    channels.write(f"{TOPIC_PREFIX}/events", "foxglove.Log",
                   {"timestamp": _stamp(verdict_ns), "level": LOG_LEVEL_INFO,
                    "message": f"verdict: {summary}", "name": "auvdiag", "file": "",
                    "line": 0}, verdict_ns)
    channels.write(f"{TOPIC_PREFIX}/verdict", "auvdiag.Verdict", {
        "verdict": report.verdict, "component": report.component,
        "candidates": list(report.candidates), "case": report.case,
        "onset_s": report.onset_s, "detected_at_s": detected,
        "summary": summary}, verdict_ns)
