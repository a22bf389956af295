"""`auvdiag inspect` on every format, and on a log that misses a profile signal."""

import re

import pytest
from typer.testing import CliRunner

from auvdiag_cli.cli import app

runner = CliRunner()
EXPECTED_TOPICS = {
    "ros": ["/thrusters/command", "/flow/velocity", "/imu/data"],
    "mavlink": ["SERVO_OUTPUT_RAW", "NAMED_VALUE_FLOAT", "ATTITUDE"],
    "dataflash": ["RCOU", "FLOW", "IMU"],
}
FAMILY = {"bag": "ros", "db3": "ros", "ros2-mcap": "ros", "mcap": "ros", "tlog": "mavlink",
          "bin": "dataflash"}


@pytest.mark.parametrize("fmt", list(FAMILY))
def test_inspect_lists_topics_counts_rates_and_signals(make_log, fmt):
    result = runner.invoke(app, ["inspect", str(make_log("routine-and-mission", 41, fmt)),
                                  "--profile", "twin_burger"])
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert f"format    {fmt} " in out
    for topic in EXPECTED_TOPICS[FAMILY[fmt]]:
        assert topic in out
    assert "50.0 Hz" in out and "10.0 Hz" in out
    assert out.count("    ok       ") == 4
    assert "segment markers: ZA ZB ZC MISSION" in out
    # How each signal reaches the model's step: the 50 Hz yaw rate averaged (anti-aliased),
    # the commands held.
    assert re.search(r"ok +yaw_rate .*averaged over each 0\.1 s step \(about 5 samples", out)
    assert re.search(r"ok +thruster_0 .*held: the last command", out)


def test_inspect_names_the_missing_signal_and_the_closest_topic(make_log, tmp_path):
    from importlib import resources

    text = (resources.files("auvdiag_cli.vehicle") / "profiles/twin_burger.toml").read_text()
    profile = tmp_path / "typo.toml"
    profile.write_text(text.replace('"/flow/velocity"', '"/flow/velocty"'))
    result = runner.invoke(app, ["inspect", str(make_log("paper-normal", 41, "db3")),
                                 "--profile", str(profile)])
    assert result.exit_code == 2
    line = next(line for line in result.stdout.splitlines() if "MISSING" in line)
    assert "flow" in line and "closest: /flow/velocity" in line


def test_inspect_of_a_damaged_log_says_so(make_log, tmp_path):
    source = make_log("paper-normal", 41, "mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(source[: len(source) // 2])
    result = runner.invoke(app, ["inspect", str(cut)])
    assert re.search(r"note: damaged at byte \d+ after \d+ messages: EndOfFile", result.stdout)
