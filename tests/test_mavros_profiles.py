"""A BlueROV2 recorded by ROS through mavros: the shipped BlueROV2 profiles read its bags
(ROS 1, ROS 2, MCAP, a per-topic CSV export) as the same dive the ground station's tlog
holds, written by the real writers with mavros's own message types, and the shipped model
judges it alike."""

from pathlib import Path

import numpy as np
import pytest
from helpers import diagnose_json

from adapters import read_log
from adapters.signals import OPERATING
from auvdiag_cli.simulator.run import simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from auvdiag_cli.vehicle.profile import Profile, load_profile

ROS_FORMATS = ("bag", "db3", "ros2-mcap", "mcap", "topic-csv")


@pytest.fixture(scope="module")
def rov() -> Profile:
    return load_profile(Path("bluerov2"))


@pytest.fixture(scope="module")
def weak_dive(rov: Profile):
    return simulate(get_scenario("mission-thruster-1-weak", rov), rov, 11)


def _written(dive, profile: Profile, folder: Path, fmt: str) -> Path:
    path = folder / (f"dive.{fmt}" if fmt in ("bag", "mcap", "tlog") else f"dive-{fmt}")
    write_log(dive, profile, path, fmt)
    return path


@pytest.mark.parametrize("fmt", ROS_FORMATS)
def test_a_mavros_bag_reads_as_the_dive_its_tlog_holds(fmt, tmp_path, rov, weak_dive):
    tlog = read_log(_written(weak_dive, rov, tmp_path, "tlog"), rov.sources)
    bag = read_log(_written(weak_dive, rov, tmp_path, fmt), rov.sources)
    assert set(bag.series) == set(tlog.series) | {OPERATING}
    for name, series in tlog.series.items():
        read = bag.series[name]
        # PWM is an integer in both; the gyro's pitch and yaw come back from ROS's frame.
        assert np.array_equal(read.times_ns // 1000, series.times_ns // 1000), name
        np.testing.assert_allclose(read.values, series.values, atol=1e-5, err_msg=name)
    armed = bag.series[OPERATING]
    assert armed.values.min() == 1 and len(armed) >= weak_dive.duration_s
    assert [m.label for m in bag.markers] == [m.label for m in tlog.markers] == ["MISSION"]
    # The DMS marker travels as a status text of severity info: no trouble.
    assert [(m.text, m.severity) for m in bag.autopilot_messages] == [("DMS MISSION", 6)]


def test_the_shipped_model_judges_the_bag_as_the_tlog(tmp_path, rov, weak_dive):
    verdicts = []
    for fmt in ("tlog", "bag"):
        status, report = diagnose_json(_written(weak_dive, rov, tmp_path, fmt),
                                       "--profile", "bluerov2")
        verdicts.append((status, report["verdict"], report["component"],
                         report["detected_at_s"]))
    assert verdicts[0] == verdicts[1] and verdicts[0][1] == "fault"


@pytest.mark.parametrize(("name", "motors"), [("bluerov2_standard", 6), ("bluerov2_heavy", 8)])
def test_the_no_dvl_profiles_read_a_mavros_bag(name, motors, tmp_path, rov, weak_dive):
    profile = load_profile(Path(name))
    mapped = profile.sources["ros"].signals
    assert [mapped[f"motor_{n}"].field for n in range(1, motors + 1)] == [
        f"channels[{n}]" for n in range(motors)]
    assert (mapped["pitch_rate"].scale, mapped["yaw_rate"].scale) == (-1.0, -1.0)
    if motors == 6:       # the BlueROV2's dive holds what the standard frame reads
        bag = read_log(_written(weak_dive, rov, tmp_path, "bag"), profile.sources)
        tlog = read_log(_written(weak_dive, rov, tmp_path, "tlog"), rov.sources)
        np.testing.assert_allclose(bag.series["yaw_rate"].values,
                                   tlog.series["yaw_rate"].values, atol=1e-6)
        assert bag.series["pitch_rate"].values.max() == 0    # the dive has no pitch
