"""The diagnosis as an MCAP (diagnose --mcap, audit --mcap): read back with the mcap library,
its topics, values and times must be the report's, on the log's own clock."""

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from typer.testing import CliRunner

from adapters import read_log
from auvdiag_cli.cli import app
from auvdiag_cli.reports.series import load_series, series_path
from auvdiag_cli.vehicle.profile import load_profile

runner = CliRunner()
SAMPLE = Path(__file__).parent.parent / "sample_logs" / "paper-flow-sensor-covered"


def read_back(path: Path) -> tuple[dict[str, list[tuple[int, dict]]], dict[str, str]]:
    messages: dict[str, list[tuple[int, dict]]] = {}
    with path.open("rb") as stream:
        reader = make_reader(stream)
        for schema, channel, message in reader.iter_messages():
            assert channel.message_encoding == "json" and schema.encoding == "jsonschema"
            messages.setdefault(channel.topic, []).append((message.log_time,
                                                           json.loads(message.data)))
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    return messages, metadata["auvdiag"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory) -> tuple[Path, dict, dict]:
    out = tmp_path_factory.mktemp("mcap")
    result = runner.invoke(app, ["diagnose", str(SAMPLE), "--json", str(out / "r.json"),
                                 "--mcap", str(out / "r.mcap"), "--quiet"])
    assert result.exit_code == 1, result.output
    report = json.loads((out / "r.json").read_text())
    return out / "r.mcap", report, load_series(series_path(out / "r.json"))


def test_topics_values_and_times_are_the_reports(exported):
    path, report, series = exported
    messages, metadata = read_back(path)
    assert set(messages) == {"/auvdiag/signals/flow", "/auvdiag/signals/yaw_rate",
                             "/auvdiag/commands", "/auvdiag/segments", "/auvdiag/events",
                             "/auvdiag/verdict"}
    # The log's own clock: the log's first message plus the report's seconds.
    first_ns = read_log(SAMPLE, load_profile().sources).start_ns
    assert int(metadata["log_start_ns"]) == first_ns
    times = np.array([t for t, _ in messages["/auvdiag/signals/flow"]])
    assert np.array_equal(times, first_ns + np.round(series["time_s"] * 1e9).astype(np.int64))
    flow = [body for _, body in messages["/auvdiag/signals/flow"]]
    column = [str(n) for n in series["sensor_names"]].index("flow")
    for key, name in (("sensor", "measured"), ("model", "modelled"), ("g_percent", "g_percent"),
                      ("threshold_percent", "thresholds")):
        got = np.array([np.nan if b[key] is None else b[key] for b in flow])
        assert np.allclose(got, series[name][:, column], rtol=1e-6, equal_nan=True), key
    assert [b["b"] for b in flow] == series["b"][:, column].tolist()
    # The substituted flow from the onset is the model's.
    after = series["time_s"] >= report["substitution"]["from_s"]
    substituted = np.array([b["substituted"] for b in flow])[after]
    assert np.allclose(substituted, series["modelled"][after, column], rtol=1e-6)
    assert "substituted" not in messages["/auvdiag/signals/yaw_rate"][0][1]
    commands = messages["/auvdiag/commands"]
    assert len(commands) == series["time_s"].size
    assert set(commands[0][1]) == {"thruster_0", "thruster_1"}


def test_verdict_onset_and_detection_are_events_at_their_times(exported):
    path, report, _ = exported
    messages, metadata = read_back(path)
    first_ns = int(metadata["log_start_ns"])
    events = {body["message"].split(":")[0]: (t, body)
              for t, body in messages["/auvdiag/events"]}
    onset_ns, onset = events["fault onset (estimated)"]
    assert onset_ns == first_ns + round(report["onset_s"] * 1e9)
    assert onset["timestamp"] == {"sec": onset_ns // 10**9, "nsec": onset_ns % 10**9}
    detected_ns, detected = events["fault detected"]
    assert detected_ns == first_ns + round(report["detected_at_s"] * 1e9)
    assert "flow_sensor" in detected["message"]
    (verdict_ns, verdict), = messages["/auvdiag/verdict"]
    assert verdict_ns == detected_ns
    assert verdict["verdict"] == "fault" and verdict["component"] == "flow_sensor"
    assert verdict["case"] == 2
    (segment_ns, segment), = messages["/auvdiag/segments"]
    assert segment["mode"] == "mission" and segment["thresholds"] == {"flow": 15.0,
                                                                      "yaw_rate": 10.0}
    assert segment_ns == first_ns + round(report["segments"][0]["start_s"] * 1e9)
    assert metadata["verdict"] == "FAULT: flow sensor"
    assert metadata["coverage"] == "2 of 2 signals and 2 of 2 actuators judged"


@pytest.mark.slow
def test_audit_writes_an_mcap_per_log_and_reuses_it(tmp_path):
    logs = tmp_path / "logs"
    logs.mkdir()
    normal = Path(__file__).parent.parent / "sample_logs" / "mission-large-cw.mcap"
    (logs / normal.name).write_bytes(normal.read_bytes())
    out = tmp_path / "audit"
    first = runner.invoke(app, ["audit", str(logs), "--output", str(out), "--jobs", "1",
                                "--mcap"])
    assert first.exit_code in (0, 1), first.output
    written = sorted((out / "logs").glob("*.mcap"))
    assert len(written) == 1
    messages, metadata = read_back(written[0])
    assert "/auvdiag/verdict" in messages and metadata["log"].endswith(normal.name)
    stamp = written[0].stat().st_mtime_ns
    again = runner.invoke(app, ["audit", str(logs), "--output", str(out), "--jobs", "1",
                                "--mcap"])
    assert "reused" in again.output or again.exit_code == first.exit_code
    assert written[0].stat().st_mtime_ns == stamp
    written[0].unlink()   # a missing MCAP is written again
    runner.invoke(app, ["audit", str(logs), "--output", str(out), "--jobs", "1", "--mcap"])
    assert written[0].is_file()
