"""Normal logs that differ no more than their own noise makes them (logs of one day, one
battery): the spread between logs then stands at what that noise allows, and a normal log
of another day may stray further. The whole log is judged against the largest spread such
logs do not rule out; the training report and a whole-log alarm judged against them say
so; logs that show offsets between them do not."""

from pathlib import Path

import numpy as np
import pytest
from quad_effort import quad_check, quad_commands, quad_model
from shared_data import SHARED_DATA

from auvdiag_cli.reports.training import effort_lines
from auvdiag_cli.vehicle.profile import load_profile
from models.chi_square import largest_spread_factor
from models.effort import ALIKE_CONFIDENCE
from models.effort_model import EffortModel, learn_effort


def test_logs_of_one_day_are_said_to_show_no_offset_and_an_alarm_against_them_says_so():
    # Three logs with no trim offset between them show none in about four draws of ten
    # (their noise sets the spread as often above as below what it allows); this seed's do.
    # Three with trims 3 % apart show theirs (40 draws of 40).
    rng = np.random.default_rng(1)
    one_day = quad_model([quad_commands(rng, np.ones(4)) for _ in range(3)])
    days = quad_model([quad_commands(rng, 1 + rng.normal(0, 0.03, 4)) for _ in range(3)])
    assert one_day.fits[0].alike and not days.fits[0].alike   # type: ignore[union-attr]
    # The spread of a handful of alike logs is where their windows' noise puts it at least,
    # widened to the upper 95 % limit of a spread estimated on its degrees of freedom.
    fit = one_day.fits[0]
    assert fit is not None
    floor = fit.within * np.sqrt(fit.window_s / fit.typical_s)
    factor = largest_spread_factor(fit.dof, ALIKE_CONFIDENCE)
    assert fit.widened == factor and 1.5 < factor < 2.5
    assert np.allclose(fit.spread, floor * factor)
    readable = one_day.to_json()["groups"][0]["normal"]
    assert readable["logs_alike"] and readable["spread_widened"] == round(factor, 4)
    assert days.fits[0].widened == 1.0                        # type: ignore[union-attr]
    # Six alike logs: dozens that show no offset show that the offsets are small.
    draws = np.random.default_rng(1)
    six = quad_model([quad_commands(draws, np.ones(4)) for _ in range(6)])
    assert six.fits[0].alike and six.fits[0].widened == 1.0   # type: ignore[union-attr]
    (line,) = effort_lines(one_day)
    assert "caution: these 3 logs differ no more than their own windows' noise" in line
    assert f"the largest spread between logs they do not rule out ({factor:.1f} times" in line
    assert "caution" not in effort_lines(days)[0]
    # A log of another day, its trim 4 % off on motor 1 from start to end: the whole log
    # departs, and the alarm says what it was judged against.
    other_day = quad_commands(rng, np.array([1.04, 1.0, 1.0, 1.0]))
    check = quad_check(one_day, other_day)
    assert check.named == ("motor_1",) and check.onset_error_s is None
    # No change within it: its share is said against normal logs only.
    assert all(a.since_onset is None for a in check.actuators)
    assert "more of the effort than on normal logs" in check.describe()
    assert check.against_alike_logs and "caution: the normal logs it is judged" in (
        check.describe())
    # Judged against logs that show their offsets, no caution (found or not).
    assert not quad_check(days, other_day).against_alike_logs


@pytest.mark.shared_data("crazypad/labels.csv")
def test_three_crazypad_flights_of_one_session_are_said_to_show_no_offset():
    """E8 normal flights 02-04 agree within their windows' noise; 00, 03 and 05 show their
    offsets."""
    from auvdiag_cli.engine.effort_check import check_effort
    from auvdiag_cli.engine.ingest import ingest
    from auvdiag_cli.jobs.effort import effort_log
    from auvdiag_cli.jobs.relate import relation_log

    profile = load_profile(Path("crazyflie"))
    folder = SHARED_DATA / "crazypad" / "E8" / "normal_flight"

    def fit(numbers: tuple[int, ...]) -> EffortModel:
        logs = [effort_log(relation_log(ingest(folder / f"E8_log{n:02d}.csv", profile),
                                        profile), profile) for n in numbers]
        model, _ = learn_effort(profile.effort_groups, logs, profile.dt_s)
        assert model is not None and model.fits[0] is not None
        return model

    one_session = fit((2, 3, 4))
    assert one_session.fits[0].alike             # type: ignore[union-attr]
    assert not fit((0, 3, 5)).fits[0].alike      # type: ignore[union-attr]
    # Judged against the largest spread they do not rule out, the other four normal flights
    # pass (against their spread as seen, 00, 01 and 06 alarmed: z 1.3-1.8 times the
    # threshold), and a cut of 3.5 mm still stands out on motor 3.
    for n in (0, 1, 5, 6):
        log = relation_log(ingest(folder / f"E8_log{n:02d}.csv", profile), profile)
        check = check_effort(one_session, profile, log.commands, log.usable,
                             profile.dt_s * np.arange(len(log.commands)))
        assert not check.suspects, n
    cut = relation_log(ingest(folder.parent / "cut_propeller_M3_3.5mm_3.5mm_40mm"
                              / "E8_log00.csv", profile), profile)
    check = check_effort(one_session, profile, cut.commands, cut.usable,
                         profile.dt_s * np.arange(len(cut.commands)))
    assert check.named == ("motor_3",) and check.against_alike_logs
