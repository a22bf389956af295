"""A log's clock against the UTC time it carries (`engine.log_clock`): a clock days off is
set right by it in every UTC time a report gives, never in the log's own seconds; a clock
within a minute of it, or a log without it, is taken as it is."""

from pathlib import Path

import numpy as np
import pytest

from adapters.signals import CLOCK_REFERENCE, Series, Signals
from auvdiag_cli.engine.log_clock import TOLERANCE_S, clock_note, utc_offset_ns, utc_start_ns
from auvdiag_cli.vehicle.profile import load_profile
from auvdiag_errors import ProfileError

START_NS = 1532133199_000_000_000           # 2018-07-21, as a clock without an RTC read it
BEHIND_S = 849091.4                         # 9.8 days: the GPS said 2018-07-30


def _signals(reference: np.ndarray | None, times_ns: np.ndarray) -> Signals:
    series = {} if reference is None else {CLOCK_REFERENCE: Series(times_ns, reference)}
    return Signals(Path("flight"), "bag", START_NS, START_NS + 10**11, series)


@pytest.mark.parametrize("unit_ns", [10**9, 10**6, 10**3, 1])
def test_a_clock_days_behind_the_time_it_carries_is_set_by_it(unit_ns):
    times = START_NS + np.arange(0, 100, 0.5) * 1e9
    utc_s = times / 1e9 + BEHIND_S + np.random.default_rng(1).normal(0, 0.2, times.size)
    signals = _signals(np.floor(utc_s * 1e9 / unit_ns), times.astype(np.int64))
    offset = utc_offset_ns(signals)
    assert offset == round(BEHIND_S) * 10**9      # to the second, whatever unit it came in
    assert utc_start_ns(signals) == START_NS + offset
    (note,) = clock_note(offset)
    assert note.startswith("the log's clock runs 9.8 days behind the UTC time it carries")


def test_a_clock_near_the_time_it_carries_or_without_one_is_taken_as_it_is():
    times = (START_NS + np.arange(0, 100, 1.0) * 1e9).astype(np.int64)
    near = _signals(times / 1e9 + TOLERANCE_S - 1.0, times)
    assert utc_offset_ns(near) == 0 and clock_note(0) == []
    assert utc_offset_ns(_signals(None, times)) == 0
    # A field that holds no date (a counter) says nothing of the clock.
    assert utc_offset_ns(_signals(np.arange(100.0), times)) == 0
    assert utc_offset_ns(_signals(np.full(100, np.nan), times)) == 0


def test_the_reference_is_read_where_a_profile_names_it_and_its_name_is_reserved():
    from auvdiag_cli.vehicle.sources import log_sources
    from auvdiag_cli.vehicle.toml_reader import TableReader

    plane = load_profile(Path("arduplane_carbonz")).sources["ros"]
    assert plane.signals[CLOCK_REFERENCE].topic == "/mavros/time_reference"
    assert CLOCK_REFERENCE in plane.optional           # a log may lack it
    table = {"signals": {"clock_reference": {"topic": "/x", "field": "data"}},
             "clock_reference": {"topic": "/gps/time", "field": "time_ref.sec"}}
    with pytest.raises(ProfileError, match="'clock_reference' is reserved for the UTC time"):
        log_sources(TableReader(table, "sources.ros"), ["clock_reference"])
