"""Shared fixtures: real logs written by the simulator through the real writers."""

from collections.abc import Callable
from pathlib import Path

import pytest
from shared_data import SHARED_DATA

from auvdiag_cli.simulator.run import SimulatedDive, simulate
from auvdiag_cli.simulator.scenarios import get_scenario
from auvdiag_cli.simulator.writers import write_log
from auvdiag_cli.vehicle.profile import Profile, load_profile

MakeLog = Callable[..., Path]


@pytest.fixture(scope="session")
def profile() -> Profile:
    return load_profile()


@pytest.fixture(scope="session")
def dive_cache(profile: Profile) -> Callable[[str, int], SimulatedDive]:
    cache: dict[tuple[str, int], SimulatedDive] = {}

    def get(scenario: str, seed: int) -> SimulatedDive:
        if (scenario, seed) not in cache:
            cache[scenario, seed] = simulate(get_scenario(scenario, profile), profile, seed)
        return cache[scenario, seed]

    return get


@pytest.fixture(scope="session")
def log_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("logs")


@pytest.fixture(scope="session")
def make_log(log_dir: Path, dive_cache: Callable[[str, int], SimulatedDive],
             profile: Profile) -> MakeLog:
    """Write (once per session) the dive of ``scenario`` with ``seed`` in ``fmt``."""

    def make(scenario: str, seed: int = 11, fmt: str = "ros2-mcap") -> Path:
        suffix = ".bag" if fmt == "bag" else ""
        path = log_dir / f"{scenario}-s{seed}-{fmt}{suffix}"
        if not path.exists():
            write_log(dive_cache(scenario, seed), profile, path, fmt)
        return path

    return make


@pytest.fixture
def profile_without(tmp_path: Path) -> Callable[[str, str], Path]:
    """The Twin-Burger profile with the text from one marker up to another cut out (a
    section it can do without), written to a file."""

    def cut(first: str, up_to: str) -> Path:
        from auvdiag_cli.vehicle.profile import profile_text

        text, _ = profile_text(None)
        path = tmp_path / f"without-{first.strip('[]').replace('.', '_')}.toml"
        path.write_text(text[:text.index(first)] + text[text.index(up_to):])
        return path

    return cut


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        missing = [SHARED_DATA / mark.args[0] for mark in item.iter_markers("shared_data")
                   if not (SHARED_DATA / mark.args[0]).exists()]
        if missing:
            item.add_marker(pytest.mark.skip(reason=f"real data not found at {missing[0]}"))
    # The slow tests first: the two workers then finish together (longest job first)
    # instead of one waiting on a late start.
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)   # stable


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Say whether the tests on real data ran: a skip is easy to miss."""
    outcomes: dict[str, str] = {}
    for outcome in ("passed", "failed", "skipped", "error"):
        for report in terminalreporter.stats.get(outcome, []):
            if "shared_data" in getattr(report, "keywords", {}):
                outcomes[report.nodeid] = outcome
    if not outcomes:
        return
    ran = sum(outcome != "skipped" for outcome in outcomes.values())
    terminalreporter.write_line(
        f"real data ({SHARED_DATA}): {ran} test(s) ran on it, "
        f"{len(outcomes) - ran} skipped" + ("" if SHARED_DATA.is_dir() else " (not found)"))
