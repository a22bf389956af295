"""A weakness the effort shares rule out: an actuator its controller drives alone (a
quadrotor's rotor) that gave a fraction of its thrust would have been driven that much
harder, and its share of the effort with it; where its share stayed in its normal band,
the weakness did not happen, however well its replay fits the motion.

A rotor giving a fraction f of its thrust needs its command raised by a = 1/sqrt(f) to
give the same thrust (thrust grows as command·|command|, as the hypothesis test replays
it); its share of the group's mean effort then rises by (a − 1)(m − 1)/(a + m − 1) among
m members, over the part of the log's steady time after the onset. The weakness is ruled
out where, to show the share observed, the log's own offset from the normal logs would have
to lie below the normal band by as much as the whole-log test's threshold lies above it
(the smallest rise it shows, `effort_naming.ActuatorEffort.smallest_rise_shown`): as
unlikely, on a normal log, as a false alarm. Where the mixer cannot drive a member alone
(a vectored ROV's four horizontal thrusters, three efforts for four), a weak one moves the
shares little (a simulated BlueROV2's thruster at 70 % moved its share 1-9 % under way)
and nothing is ruled out. A dead one pushed to its limit is held to the rise a quarter of
its thrust asks, the least it shows."""

import math

import numpy as np

from auvdiag_cli.engine.effort_check import EffortCheck
from auvdiag_cli.engine.effort_naming import ActuatorEffort

LEAST_FRACTION = 0.25


def expected_rise(fraction: float, members: int) -> float:
    """How much more than its normal share a member giving ``fraction`` of its thrust
    carries, its controller restoring the thrust through it alone."""
    raised = 1.0 / math.sqrt(max(fraction, LEAST_FRACTION))
    return (raised - 1.0) * (members - 1) / (raised + members - 1)


def _after(effort: EffortCheck, group: str, onset_s: float) -> float:
    """The share of the group's judged steady time after ``onset_s``: its windows are
    consecutive, each from the last one's end to its own (the first as long as the second)."""
    series = next((s for s in effort.series if s.group == group), None)
    if series is None or len(series.time_s) < 2:
        return 0.0
    ends = np.asarray(series.time_s, float)
    begins = np.concatenate([[2 * ends[0] - ends[1]], ends[:-1]])
    with np.errstate(invalid="ignore", divide="ignore"):
        after = np.clip((ends - onset_s) / (ends - begins), 0.0, 1.0)
    return float(np.nan_to_num(after).mean())


def ruled_out_by_shares(effort: EffortCheck | None, component: str, fraction: float,
                        onset_s: float, weakness: str) -> str | None:
    """Why ``weakness`` (``component`` giving ``fraction`` of its thrust from ``onset_s``)
    did not happen, in the words of a report; None where the shares cannot say."""
    if effort is None:
        return None
    own = [a for a in effort.actuators if a.component == component]
    if len(own) != 1 or not _judged_alone(own[0]):
        return None
    actuator = own[0]
    members = sum(a.group == actuator.group for a in effort.actuators)
    rise = expected_rise(fraction, members) * _after(effort, actuator.group, onset_s)
    departure, shown = actuator.departure or 0.0, actuator.smallest_rise_shown or 0.0
    if rise <= 0 or departure - rise > -shown:
        return None
    return (f"its share of the effort departed {departure:+.0%} from normal, where {weakness} "
            f"would have carried about {rise:.0%} more over this log (its controller drives "
            f"it alone, and this log's shares show a rise of {shown:.0%} or more)")


def _judged_alone(actuator: ActuatorEffort) -> bool:
    return (actuator.not_judged is None and actuator.driven_alone
            and not actuator.driven_harder and actuator.departure is not None
            and actuator.smallest_rise_shown is not None)
