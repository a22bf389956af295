"""The verdict's onset is the sharpest dating of its event: where the judge that saw it
first dates it to within seconds and another judge that names the same part dates it,
within both their errors, to within tenths, the verdict takes the second; a judge that
names another part, dates another event, or began after the detection changes nothing."""

from dataclasses import replace

import numpy as np
from helpers import observed

from auvdiag_cli.engine.change_check import ChangeCheck
from auvdiag_cli.engine.command_check import CommandCheck
from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.effort_naming import ActuatorEffort
from auvdiag_cli.engine.onset_dating import sharpest_onset
from auvdiag_cli.engine.results import Finding, Verdict
from auvdiag_cli.reports.report import Report
from auvdiag_cli.reports.sentences import when_sentence
from auvdiag_cli.reports.text import summary_lines

STOPPED_S = 130.5       # when the simulated thruster stopped


def _effort(onset_s: float, error_s: float) -> EffortCheck:
    actuators = tuple(ActuatorEffort(f"motor_{i}", f"thruster_{i}", "vertical", 1.0, 1.0,
                                     0.02, 0.0, 2.0 if i == 5 else 0.5, None) for i in (5, 6))
    return EffortCheck(actuators, 0.01, 133.0, onset_s, ("thruster_5",), (),
                       onset_error_s=error_s)


def _commands(named: tuple[str, ...], began_s: float, error_s: float) -> CommandCheck:
    return CommandCheck(("thruster_5", "thruster_6"), {}, {}, np.zeros((1, 2)), (), 134.2,
                        134.0, named, {"thruster_5": 1.0}, 1.06, 15.0, "thrust lost", None,
                        began_s, error_s)


def _finding(onset_s: float) -> Finding:
    return Finding(verdict=Verdict.FAULT, b={}, component="thruster_5",
                   candidates=("thruster_5",), detected_at_s=133.0, onset_s=onset_s)


def test_the_sharper_dating_of_the_same_part_and_event_is_the_verdicts():
    seen = replace(observed(_effort(128.0, 2.6), {}),
                   command_check=_commands(("thruster_5",), 130.65, 0.2))
    dated = sharpest_onset(_finding(128.0), seen)
    assert dated.onset_s == 130.65 and abs(dated.onset_s - STOPPED_S) < 0.2
    assert dated.onset_error_s == 0.2
    assert dated.notes[-1] == (
        "dated by the commands against the motion, the sharpest of the judges that saw it: "
        "it began at ~130.7 s (give or take 0.2 s; the effort shares: ~128.0 s, give or "
        "take 2.6 s)")


def test_another_part_another_event_or_a_vaguer_dating_changes_nothing():
    effort = observed(_effort(128.0, 2.6), {})
    for command in (_commands(("thruster_6",), 130.65, 0.2),     # another part
                    _commands(("thruster_5",), 131.5, 0.2),      # outside both errors
                    _commands(("thruster_5",), 128.5, 3.0)):     # no sharper
        finding = sharpest_onset(_finding(128.0), replace(effort, command_check=command))
        assert finding.onset_s == 128.0 and not finding.notes
        assert finding.onset_error_s == 2.6      # the effort shares' own
    # The verdict's onset from a judge that states no error (the replay's) stays.
    seen = replace(effort, command_check=_commands(("thruster_5",), 130.65, 0.2))
    replayed = sharpest_onset(_finding(127.0), seen)
    assert replayed.onset_s == 127.0 and replayed.onset_error_s is None
    # Not a fault: nothing to date.
    normal = replace(_finding(128.0), verdict=Verdict.UNDETERMINED)
    assert sharpest_onset(normal, seen) == normal


def test_the_report_says_the_onsets_error():
    report = Report(log="dive.tlog", verdict="fault", detected_at_s=133.0, onset_s=130.65,
                    onset_error_s=0.2)
    assert when_sentence(report).startswith("onset about 130.7 s (give or take 0.2 s), "
                                            "detected at 133.0 s")
    assert "onset    ~130.7 s (give or take 0.2 s)   detected 133.0 s" in "\n".join(
        summary_lines(report))
    assert "give or take" not in when_sentence(replace(report, onset_error_s=None))
    assert report.to_json()["onset_error_s"] == 0.2


def test_a_change_dated_in_its_reference_states_no_error():
    """The change test dates its own verdict within its error; one that may have begun in
    the log's beginning it judges against is "or earlier", unbounded."""
    change = ChangeCheck({}, {}, 20.0, 133.0, 128.0, 1.5)
    seen = replace(observed(None, {}), change_check=change)
    assert sharpest_onset(_finding(128.0), seen).onset_error_s == 1.5
    earlier = replace(seen, change_check=replace(change, since_judged=True))
    assert sharpest_onset(_finding(128.0), earlier).onset_error_s is None
