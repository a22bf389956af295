"""CSV logs: written by the simulator from the profile's [sources.csv] columns, read back with
every time unit; bad rows counted, never fatal; recognised by content; the real Haizhe runs
read as they are."""

import re
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_outcome, zeroed_column
from shared_data import SHARED_DATA
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
PROFILE = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
HAIZHE = SHARED_DATA / "haizhe" / "train"


@pytest.fixture(scope="module")
def reference(make_log):
    return diagnose_outcome(make_log("paper-flow-sensor-covered", 31, "mcap"))[1]


@pytest.mark.parametrize("unit", ["s", "ms", "us", "ns", "iso", "hhmmss"])
def test_csv_round_trip_in_every_time_unit(tmp_path, dive_cache, reference, unit):
    from auvdiag_cli.simulator.writers import write_log
    from auvdiag_cli.vehicle.profile import load_profile

    profile_path = tmp_path / "p.toml"
    profile_path.write_text(PROFILE.replace('unit = "s" }', f'unit = "{unit}" }}'))
    profile = load_profile(profile_path)
    log = tmp_path / "dive.csv"
    write_log(dive_cache("paper-flow-sensor-covered", 31), profile, log, "csv")
    code, report = diagnose_outcome(log, "--profile", str(profile_path))
    assert code == 1 and report["format"] == "csv"
    assert report["component"] == reference["component"] == "flow_sensor"
    if unit == "hhmmss":   # rows spread over each second: times are right to a fraction of it
        assert abs(report["onset_s"] - reference["onset_s"]) < 1.0
        assert any("one-second resolution" in note for note in report["notes"])
    else:
        assert report["onset_s"] == pytest.approx(reference["onset_s"], abs=0.01)
        assert report["segments"][0]["max_g"] == pytest.approx(
            reference["segments"][0]["max_g"], rel=1e-3)


def _rows(log: Path) -> list[str]:
    return log.read_text().splitlines()


def test_bad_rows_are_counted_not_fatal(make_log, tmp_path):
    lines = _rows(make_log("paper-normal", 11, "csv"))
    width = lines[0].count(",")
    damaged = lines[:200] + ["1,2,3"] + lines[200:400] + ["not a time" + "," * width] \
        + [re.sub(r",([-\d.e]+)$", ",oops", line) for line in lines[400:403]] + lines[403:] \
        + [lines[-1][:7]]                                          # a row cut short
    log = tmp_path / "damaged.csv"
    log.write_text("\n".join(damaged) + "\n")
    code, report = diagnose_outcome(log)
    assert code == 0
    note = next(n for n in report["notes"] if n.startswith("left out:"))
    assert "2 row(s) with the wrong number of cells" in note
    assert "1 row(s) whose time does not read" in note
    assert re.search(r"[1-3] cell\(s\) that are not numbers", note)


def test_a_csv_with_no_usable_row_is_one_line(tmp_path):
    log = tmp_path / "empty.csv"
    log.write_text("time_s,thruster_0,thruster_1,flow_mps,yaw_rate_rps,sequence\n"
                   "x,1,2,3,4,\n")
    code, line = diagnose_outcome(log)
    assert code == 2 and str(log) in line and "\n" not in line


def test_a_missing_column_names_it_and_the_closest(make_log, tmp_path):
    text = make_log("paper-normal", 11, "csv").read_text()
    log = tmp_path / "renamed.csv"
    log.write_text(text.replace("flow_mps", "flow_m_s", 1))
    code, line = diagnose_outcome(log)
    assert code == 2 and "no column(s) flow_mps in the header" in line
    assert "closest first: flow_m_s" in line


def test_columns_named_with_units_and_dashes_are_read_drafted_and_trained_on(make_log,
                                                                          tmp_path):
    """A CSV column is a name, not a field path: "flow (m/s)" and "thr-0 [cmd]" read as
    the plain names do, from a hand-written profile and from `init-profile`'s draft, which
    takes "time (s)" for the clock and its unit from the brackets."""
    renamed = {"time_s": "time (s)", "flow_mps": "flow (m/s)", "thruster_0": "thr-0 [cmd]"}
    logs = []
    for seed in (11, 12):
        text = make_log("paper-normal", seed, "csv").read_text()
        header, rest = text.split("\n", 1)
        for old, new in renamed.items():
            assert old in header.split(",")
            header = header.replace(old, new)
        logs.append(tmp_path / f"dive{seed}.csv")
        logs[-1].write_text(header + "\n" + rest)
    profile = tmp_path / "units.toml"
    text = PROFILE
    for old, new in renamed.items():
        text = text.replace(f'column = "{old}"', f'column = "{new}"')
    profile.write_text(text)
    runner = CliRunner()
    shown = runner.invoke(app, ["inspect", str(logs[0]), "--profile", str(profile)])
    assert shown.exit_code == 0, shown.output
    assert re.search(r"ok\s+flow\s+flow \(m/s\)", shown.output)
    trained = runner.invoke(app, ["train", *map(str, logs), "--profile", str(profile),
                                  "--output", str(tmp_path / "model"), "--iterations-scale",
                                  "0.05", "--keep-unskilled"])
    assert trained.exit_code == 0, trained.output
    drafted = runner.invoke(app, ["init-profile", str(logs[0]), "-o",
                                  str(tmp_path / "draft.toml")])
    assert drafted.exit_code == 0, drafted.output
    draft = (tmp_path / "draft.toml").read_text()
    assert 'column = "flow (m/s)"' in draft and 'time = { column = "time (s)", unit = "s" }' \
        in draft
    checked = runner.invoke(app, ["inspect", str(logs[0]), "--profile",
                                  str(tmp_path / "draft.toml")])
    assert checked.exit_code == 0 and "flow (m/s)" in checked.output, checked.output


def test_csv_is_recognised_by_content_not_by_name(make_log, tmp_path):
    from adapters import detect_format
    from auvdiag_errors import LogError

    text = make_log("paper-normal", 11, "csv").read_text()
    (tmp_path / "dive.txt").write_text(text)
    assert detect_format(tmp_path / "dive.txt") == "csv"
    (tmp_path / "notes.csv").write_text("just some notes\nabout the dive\n")
    (tmp_path / "binary.csv").write_bytes(bytes(range(256)) * 4)
    for name in ("notes.csv", "binary.csv"):
        with pytest.raises(LogError, match="not a log"):
            detect_format(tmp_path / name)


def test_hhmmss_rows_are_spread_evenly_over_each_second():
    from adapters.csv_log import _times_ns
    from adapters.signals import TimeColumn

    texts = ["235958"] * 3 + ["235959"] * 4 + ["000000"] * 4 + ["000001"] * 2
    notes: list[str] = []
    times = _times_ns(texts, TimeColumn("time", "hhmmss"), notes) / 1e9
    assert np.all(np.diff(times) > 0)                       # midnight does not go back
    assert times[3:7] == pytest.approx(86399 + np.arange(4) / 4)
    assert times[:3] == pytest.approx(86398 + 1 - np.arange(3, 0, -1) / 4)   # end of its second
    assert times[-2:] == pytest.approx(86401 + np.arange(2) / 4)             # start of its own
    assert "about 4 rows a second" in notes[0]


@pytest.mark.shared_data("haizhe/train")
def test_real_haizhe_runs_are_read_directly():
    from adapters import read_log
    from auvdiag_cli.vehicle.profile import load_profile

    profile = load_profile(Path("haizhe"))
    log = HAIZHE / "Normal" / "Normal_0.csv"
    shown = runner.invoke(app, ["inspect", str(log), "--profile", "haizhe"])
    assert shown.exit_code == 0 and "MISSING" not in shown.stdout
    signals = read_log(log, profile.sources)
    times = signals.series["depth"].times_ns
    rows = len(log.read_text().splitlines()) - 1
    assert len(times) == rows and np.all(np.diff(times) > 0)
    assert 18 <= rows / ((times[-1] - times[0]) / 1e9) <= 22          # about 20 rows a second
    assert np.abs(signals.series["yaw_rate"].values).max() < 2.0               # deg/s read as rad/s


def test_a_csv_log_of_another_vehicle_names_the_shipped_profile_that_reads_it(tmp_path):
    """Columns named as the Haizhe AUV logs them: the default profile cannot read the file,
    and the one-line error says which shipped profile can."""
    from typer.testing import CliRunner

    from auvdiag_cli.cli import app

    log = tmp_path / "run.csv"
    rows = ["time,pwm1,pwm2,pwm3,pwm4,depth,voltage,roll,pitch,w_row,w_pitch,w_yaw"]
    rows += [f"{120000 + k // 20},1500,1500,1500,1500,{0.01 * k},12.1,1.5,-0.5,0.1,0.2,0.3"
             for k in range(60)]
    log.write_text("\n".join(rows) + "\n")
    result = CliRunner().invoke(app, ["diagnose", str(log)])
    assert result.exit_code == 2
    line, = result.output.strip().splitlines()
    assert line.endswith("the shipped profiles that fit this log: haizhe (--profile NAME)")


def test_a_channel_never_fed_sets_no_threshold_in_calibrate(make_log, tmp_path):
    """Calibrated with a log whose flow was never fed beside normal ones, the flow's
    threshold is what the normal logs give: that log's flow g (the model's speed against a
    channel that reads 0) says nothing of the model."""
    from auvdiag_cli import api

    normal = [make_log("paper-normal", seed, "csv") for seed in (3, 4)]
    flat = zeroed_column(make_log("paper-normal", 5, "csv"), "flow_mps",
                        tmp_path / "no_flow.csv")
    profile = api.load_profile(None)

    def thresholds(logs: list[Path]) -> dict[str, float]:
        model = api.load_model(None, profile)
        api.calibrate(logs, profile, model)
        return dict(model.card.thresholds["mission"])

    alone, beside = thresholds(normal), thresholds([*normal, flat])
    assert beside["flow"] == pytest.approx(alone["flow"], rel=0.02)
    assert beside["yaw_rate"] >= alone["yaw_rate"]


def test_a_sensor_that_reads_one_value_throughout_is_named_and_not_judged(make_log, tmp_path):
    """A channel written but never fed (zeros in every one of its cells) is named in a note
    and left unjudged in that log; a sensor that moves is judged, and a short stretch alike
    is no flat channel."""
    from auvdiag_cli.engine.flat_signals import flat_sensors

    log = zeroed_column(make_log("paper-normal", 11, "csv"), "flow_mps", tmp_path / "no_flow.csv")
    _, report = diagnose_outcome(log)
    assert isinstance(report, dict)
    flat = [n for n in report["notes"] if "throughout the log" in n]
    assert len(flat) == 1 and flat[0].startswith("flow reads 0 throughout"), flat
    assert report["coverage"]["signals"]["not_judged"] == ["flow"]
    assert "reads 0 throughout" in report["not_judged"]["flow"]
    _, normal = diagnose_outcome(make_log("paper-normal", 11, "csv"))
    assert isinstance(normal, dict)
    assert not [n for n in normal["notes"] if "throughout the log" in n]
    assert normal["coverage"]["signals"]["not_judged"] == []
    still = np.zeros((99, 1))
    assert flat_sensors(still, ("depth",), 0.1) == {}
    assert list(flat_sensors(np.vstack([still, [[np.nan]], still]), ("depth",), 0.1)) == [
        "depth"]
