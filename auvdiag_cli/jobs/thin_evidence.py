"""What `calibrate` warns of when its normal logs cannot show how much the next normal log
may differ: too few of them for the margin rule, or all of one day."""

from collections.abc import Sequence

from auvdiag_cli.engine.ingest import IngestedLog
from auvdiag_cli.engine.log_clock import utc_start_ns
from auvdiag_cli.engine.results import utc_day
from auvdiag_cli.engine.settled import SETTLED_LOGS
from models.false_alarms import MIN_LOGS


def thin_evidence(logs: Sequence[IngestedLog], budgeted: bool,
                  change_logs: int | None = None, unseen: int | None = None) -> list[str]:
    """The warnings: fewer logs than a law needs, where the margin rule sets thresholds (all
    of them, or with ``budgeted`` those g's blocks do not: the largest of a few peaks
    understates the next normal log's; the change test's rest on ``change_logs``, the
    training logs the model keeps counted too); fewer than SETTLED_LOGS the model was not
    trained on (``unseen``), whose replay alarms are then judged as those of thresholds no
    calibration set (`slight_alarm`); fewer than SETTLED_LOGS behind the change test's
    (`slight_change`); and logs of a single day (on UTC clocks), whose
    wind, sea state and payload say nothing of another day's."""
    warnings = []
    if unseen is not None and unseen < SETTLED_LOGS:
        warnings.append(
            f"{unseen} of the calibration logs {'was' if unseen == 1 else 'were'} not used to "
            "train the model: until it is "
            f"calibrated on {SETTLED_LOGS} or more such logs, an alarm of the replay alone "
            "that crosses these thresholds by less than a quarter, or that no single fault "
            "explains, is undetermined, not a fault")
    if change_logs is not None and change_logs < SETTLED_LOGS:
        warnings.append(
            f"the change test's thresholds rest on {change_logs} normal log(s) (those the "
            f"model was trained on included): until {SETTLED_LOGS} or more, a change-test "
            "alarm that no other judge bears out and that crosses them by less than a "
            "quarter is undetermined, not a fault")
    if len(logs) < MIN_LOGS:
        ruled = ("the change test's thresholds (and the commands')"
                 if (len(logs) if change_logs is None else change_logs) < MIN_LOGS
                 else "the commands' thresholds (the change test's count the logs trained on)")
        which = (f"{ruled} take the margin rule" if budgeted else "the margin times the "
                 "largest of so few peaks is often reached by the next normal log")
        warnings.append(f"{len(logs)} calibration log(s): {which}; add normal logs (the "
                        "training logs count too: their in-sample g is widened)"
                        + ("" if budgeted else ", or set --false-alarm-rate, which fits each "
                           "signal's g to blocks of these logs"))
    days = utc_days(logs)
    if len(days) == 1:
        warnings.append(f"every calibration log was recorded on {days[0]}: the thresholds "
                        "have seen one day's conditions (wind or current, sea state, payload), "
                        "and logs of other days may reach past them; calibrate on logs of "
                        "several days")
    return warnings


def utc_days(logs: Sequence[IngestedLog]) -> tuple[str, ...]:
    """The UTC days (ISO dates) the logs were recorded on, where every log's clock is UTC
    (none where one is a clock since boot: its day is not known)."""
    days = [utc_day(utc_start_ns(log.signals)) for log in logs]
    return () if None in days else tuple(sorted({day for day in days if day}))
