"""What `auvdiag train` and `auvdiag calibrate` print: where the model went, its skill per
signal against the naive predictors and the horizon chosen (the paper's figures for the
paper's vehicle only); the thresholds, which log set each, and what to be wary of."""

import math
from collections.abc import Collection, Sequence

from auvdiag_cli.engine.change_check import MIN_JUDGED_S
from auvdiag_cli.engine.effort_spans import smallest_later_rise, typical_later_threshold
from auvdiag_cli.engine.effort_words import rise_range
from auvdiag_cli.engine.envelope import MARGIN
from auvdiag_cli.engine.judging import own_log_only
from auvdiag_cli.jobs.budget import BudgetThresholds
from auvdiag_cli.jobs.calibration_result import CalibrationResult, ModeCalibration
from auvdiag_cli.jobs.train import TrainingResult
from auvdiag_cli.reports.sentences import by_reason
from auvdiag_cli.vehicle.profile import Profile
from models.card import Refused, StartReference
from models.effort import FEW_LOGS, EffortGroup, GroupFit
from models.effort_model import EffortModel, GroupSetup
from models.effort_thresholds import NEAR_RATE, Thresholds, smallest_rise, widening
from models.fast import NETWORK
from models.relation_forms import Relations
from models.skill import MIN_SCORED_SAMPLES, MIN_SKILL, SKILL_MARGIN, HorizonScore, SignalSkill


def horizon_text(horizon_s: float | None) -> str:
    return "free run" if horizon_s is None else f"{horizon_s:g} s"


def _number(value: float) -> str:
    return f"{value:9.4f}" if math.isfinite(value) else f"{value!s:>9}"


def _ratio(value: float) -> str:
    """A skill-like ratio in 7 characters: far below zero is only 'worse'."""
    return f"{value:7.2f}" if not value < -99 else f"{'< -99':>7}"


def _verdict(s: SignalSkill, own_log_only: bool) -> str:
    if own_log_only:
        return OWN_LOG_ONLY
    if not s.enough_data:
        return (f"NO: too little held-out data to measure it ({s.samples} samples, needs "
                f"{MIN_SCORED_SAMPLES})")
    return "yes" if s.judged else "NO: not judged (the model cannot predict it)"


# The judged column of a signal the profile judges only against the log's own beginning.
OWN_LOG_ONLY = "change test only"


def _skill_rows(score: HorizonScore, own_log_only: Collection[str]) -> list[str]:
    baselines = list(next(iter(score.signals.values())).baseline_rms)
    rows = [f"  {'signal':<14}{'predictor':<19}{'skill':>7}{'vs linear':>10}{'model':>10}"
            + "".join(f"{name:>10}" for name in baselines) + "   judged"]
    for name, s in score.signals.items():
        rows.append(f"  {name:<14}{score.predictors.get(name, NETWORK):<19}{_ratio(s.skill)}"
                    f"   {_ratio(s.versus_linear)} {_number(s.model_rms)}"
                    + "".join(f" {_number(s.baseline_rms[b])}" for b in baselines)
                    + f"   {_verdict(s, name in own_log_only)}")
    if any(name in own_log_only for name in score.signals):
        rows.append(f"  {OWN_LOG_ONLY}: the profile judges it only against the log's own "
                    "beginning (the change test, with the predictor a moment ahead), never by "
                    "this replay, whatever its skill here")
    return rows


def predictor_lines(result: TrainingResult) -> list[str]:
    """Each predictor's skill per signal at the horizon chosen: why each signal is read
    from the one it is."""
    horizons = [s.horizon_s for s in result.scores]
    at = horizons.index(result.chosen.horizon_s)
    if len(result.by_predictor) < 2:
        return [f"  left out: {note}" for note in result.predictor_notes]
    lines = [f"skill per predictor at {horizon_text(result.chosen.horizon_s)} (each signal is "
             "read from the best; a more complex one must win by "
             f"{SKILL_MARGIN:g}):"]
    for name in result.chosen.signals:
        lines.append(f"  {name:<14}" + ", ".join(
            f"{kind} {_ratio(scores[at].signals[name].skill).strip()}"
            for kind, scores in result.by_predictor.items()))
    return lines + [f"  left out: {note}" for note in result.predictor_notes]


def skill_lines(scores: Sequence[HorizonScore], chosen: HorizonScore,
                own_log_only: Collection[str] = ()) -> list[str]:
    """The horizon chosen and each signal's skill there (``own_log_only``: the signals the
    profile judges only against the log's own beginning)."""
    tried = ", ".join(f"{horizon_text(s.horizon_s)} {len(s.judged)}/{len(s.signals)}"
                      for s in scores)
    lines = [f"prediction horizon: {horizon_text(chosen.horizon_s)}"
             + (f" (signals judged per horizon tried: {tried})" if len(scores) > 1 else "")]
    lines.append("skill on held-out normal data = 1 - rms_model / the better naive rms "
                 f"(the last value holds, the training mean), judged from {MIN_SKILL:.2f}; "
                 "vs linear: the same against a least-squares linear model. rms in the "
                 "signals' units:")
    return lines + _skill_rows(chosen, own_log_only)


def training_lines(result: TrainingResult, paper_rms: dict[str, float], profile: Profile
                   ) -> list[str]:
    chosen = result.chosen
    lines = [f"model {'written to ' + str(result.output) if result.written else 'NOT written'}"
             f" ({result.training_logs} training log(s), {result.operating_hours:.2f} h of "
             f"operating time; held out: {result.heldout_split})"]
    if result.input_names:
        lines.append("driven by the commands and the measured inputs "
                     f"{', '.join(result.input_names)} (replayed as logged)")
    lines += skill_lines(result.scores, chosen, own_log_only(profile)) + predictor_lines(result)
    if paper_rms:
        lines.append("the paper's model error for this vehicle (rms): "
                     + ", ".join(f"{k} {v}" for k, v in paper_rms.items()))
    if result.envelope:
        units = {s.name: s.unit for s in profile.sensors}
        lines.append(f"learnt up to (a fault found after a judged signal went past {MARGIN:g} "
                     "times this is undetermined): " + ", ".join(
                         f"{name} {value:.3g} {units.get(name, '')}".rstrip()
                         for name, value in result.envelope.items()))
    if result.thresholds_raised:
        lines.append("g thresholds: the profile's, raised to 1.5 x the largest g the held-out "
                     "log(s) reached where that is more (" + ", ".join(result.thresholds_raised)
                     + "); 'auvdiag calibrate' on normal logs the model has not seen sets "
                       "them anew")
    groups = ([] if isinstance(result.effort, Refused)
              else [setup.group for setup in result.effort.setups])
    return lines + relation_lines(result.command_relations, profile.command_names,
                                  groups) + start_lines(
        result.start_state, profile.sensor_names) + effort_lines(result.effort) + [
        f"  left out: {note}" for note in result.effort_notes]


def _listed(names: Sequence[str], most: int = 5) -> str:
    shown = ", ".join(names[:most])
    return shown if len(names) <= most else f"{shown} and {len(names) - most} more"


def relation_lines(relations: Relations | Refused, command_names: Sequence[str],
                   effort_groups: Sequence[EffortGroup] = ()) -> list[str]:
    """How the commands follow the motion: learned from which logs, in which form and why,
    and the extra effort (or thrust lost) each actuator may show before it is called
    weakened (and, for actuators this check cannot tell apart, the ``effort_groups`` whose
    shares can)."""
    if isinstance(relations, Refused):
        return [f"commands not judged against the motion: {relations.reason}"]
    fitted = relations.fitted_on
    left_out = list(fitted.open_loop_left_out)
    lines = [f"command relations learned from {len(fitted.logs)} log(s), {fitted.steps} steps"
             + (f" (left out as open loop: {_listed(left_out)})" if left_out else "")
             + f"; {relations.measure} allowed per "
             f"{relations.window_steps * relations.dt_s:g} s window:"]
    if fitted.chosen:
        lines.insert(1, f"  kept: {fitted.chosen}")
    groups = [[command_names[k] for k in g] for g in relations.groups if len(g) > 1]
    for k, (name, threshold, skill) in enumerate(zip(
            command_names, relations.thresholds.tolist(), relations.skill.tolist(),
            strict=True)):
        if math.isnan(skill) or skill < MIN_SKILL:
            allowed = f"not judged ({relations.unpredicted(k)})"
        else:
            shorter = "".join(f", {w.thresholds[k]:.0%} per {w.steps * relations.dt_s:g} s"
                              for w in relations.shorter if not math.isnan(w.thresholds[k]))
            allowed = (f"{threshold:.0%}" if not math.isnan(threshold) else
                       f"not judged ({relations.too_little_heldout(k)})" if not shorter else
                       "none") + shorter
        lines.append(f"  {name:<14}{allowed}" + ("" if math.isnan(skill) else
                                                 f"   (skill {skill:.2f})"))
    for g in groups:
        apart = [e.name for e in effort_groups if set(g) <= set(e.members)]
        lines.append(f"  {' and '.join(g)} act alike on the vehicle: this check names a "
                     "weakness as either" + (f" (the effort shares of {apart[0]} tell them "
                                             "apart)" if apart else ""))
    return lines


def start_lines(start: StartReference, sensor_names: Sequence[str]) -> list[str]:
    """Where normal logs start, and how far a log's start may lie from it."""
    if start.refused is not None:
        return [f"start not judged: {start.refused}"]
    return [f"start learned from {start.logs} log starts (first {start.span_s:g} s); "
            "allowed from the normal start: " + ", ".join(
                f"{name} {reference:.3g} ± {allowed:.3g}" if allowed is not None else
                f"{name} not judged (normal starts spread)" for name, reference, allowed in zip(
                    sensor_names, start.reference, start.thresholds, strict=True))]


def effort_lines(effort: EffortModel | Refused) -> list[str]:
    """Lines for `train` and `calibrate`: per group, each actuator's normal share and
    spread, the threshold and the false-alarm budget, or why it is not judged."""
    if isinstance(effort, Refused):
        return [f"effort: {effort.reason}"]
    lines = []
    changes = effort.change_fits or (None,) * len(effort.setups)
    for setup, logs, fit, why, change in zip(effort.setups, effort.summaries, effort.fits,
                                             effort.refused, changes, strict=True):
        group = setup.group
        if fit is None or effort.thresholds is None:
            lines.append(f"effort of {group.name}: {why}")
            continue
        parts = ", ".join(f"{m} {s:.3f} ± {d:.3f}" for m, s, d in zip(
            group.members, fit.means.mean(axis=0), fit.spread, strict=True))
        lines.append(
            f"effort of {group.name} ({len(logs)} normal logs, {setup.window_s:.1f} s windows"
            f"{', by level' if fit.conditioned else ''}): share {parts}; driven harder past "
            f"z {effort.thresholds.whole_log(fit):.2f} (false alarms budgeted at "
            f"{effort.false_alarm_rate:.1%} of normal logs; each normal log judged by the "
            f"others: largest z {float(fit.loo_z.max()):.2f}{_scatter(fit)})"
            f"{_not_ruled_out(fit, effort.thresholds)}; changed within a log past z "
            f"{typical_later_threshold(setup, fit, effort.thresholds, effort.dt_s, change):.2f}"
            + _later_noise(setup, fit, change)
            + _smallest(setup, fit, effort.thresholds, effort.dt_s, change) + _alike(fit))
    return lines


def _not_ruled_out(fit: GroupFit, thresholds: Thresholds) -> str:
    """Where the few normal logs leave a band under the threshold undetermined."""
    near = thresholds.near(fit)
    return "" if near is None else (
        f"; from z {near:.2f} (the threshold of a {NEAR_RATE:.0%} budget) to it, a log whose "
        f"shares match one actuator's weakness is undetermined: fewer than {FEW_LOGS} normal "
        "logs cannot rule that weakness out")


def _later_noise(setup: GroupSetup, fit: GroupFit, change: GroupFit | None) -> str:
    """What the test of a change within a log is judged over, and its noise."""
    change = setup.bin_fit(change)
    if change is None:
        return (f" (a log of {fit.typical_s:.0f} s of steady effort; its windows' noise rests "
                f"on {fit.within_dof:.0f} degrees of freedom)")
    return (f" (a log of {change.typical_s:.0f} s of steady effort in the thrust direction "
            "that holds most of the normal logs' effort, judged there along the mixer's "
            f"signatures in {change.window_s:.1f} s windows whose noise, the thrusters moving "
            f"together included, rests on {change.within_dof:.0f} degrees of freedom)")


def _smallest(setup: GroupSetup, fit: GroupFit, thresholds: Thresholds, dt_s: float,
              change: GroupFit | None) -> str:
    """The smallest weakness each test judges, in terms a user can weigh, and what twice the
    normal logs would bring the whole log's to. A change judged along the mixer's signatures
    depends on the log's own thrust, so no one rise is said for it."""
    more = 2 * fit.logs
    whole = (f"; one weak actuator is judged once it carries about "
             f"{rise_range(list(smallest_rise(fit, thresholds)))} more than its share over a "
             f"log of {fit.typical_s:.0f} s (with {more} normal logs, about "
             f"{rise_range(list(smallest_rise(fit, thresholds, more)))})")
    if setup.bin_fit(change) is not None:
        return whole
    return (whole + ", or, where it weakens halfway through such a log, about "
            f"{rise_range(list(smallest_later_rise(setup, fit, thresholds, dt_s)))} more from "
            "then on (against the log's own first half)")


def _scatter(fit: GroupFit) -> str:
    """Where the normal logs scatter wider than Student's t says, past what chance gives."""
    factor = widening(fit)
    return "" if factor <= 1.0 else (
        f"; they scatter {factor:.2f} times as wide as Student's t says, past chance, and "
        "the threshold is widened as much")


def _alike(fit: GroupFit) -> str:
    """A caution where the normal logs agree within their own noise: the spread between
    logs then stands at what that noise allows, and logs of another day may stray further."""
    if not fit.alike:
        return ""
    judged = "" if fit.widened <= 1.0 else (
        "a whole log is judged against the largest spread between logs they do not rule out "
        f"({fit.widened:.1f} times theirs), and ")
    return (f"; caution: these {fit.logs} logs differ no more than their own windows' noise "
            "makes them (no offset between logs shows, as on logs of one day or one "
            f"battery): {judged}a normal log of another day may stray further"
            f"{' still' if judged else ' than these thresholds allow'}; train on normal logs "
            "of more than one day")


def budget_lines(budget: BudgetThresholds, hours: float) -> list[str]:
    """What `calibrate --false-alarm-rate` set, and how it held up leaving each log out."""
    per_log = ("" if not budget.budget.per_hour
               else f" (a share of {budget.per_log_rate:.2%} of logs of the median length)")
    lowered = ("" if not budget.lowered else
               f", lowered for {', '.join(f.judge.label for f in budget.lowered)} because "
               "its logs left out alarmed more often than its fitted law promises")
    lines = [f"calibrated on {hours:.2f} h of normal data ({budget.logs} logs) for a "
             f"false-alarm rate of {budget.budget.describe()}{per_log}: its judges move "
             f"as {budget.independent:.1f} independent ones would, and each gets "
             f"{budget.share:.2%} of logs{lowered}",
             f"  leave one log out: {budget.loo_logs_alarmed} of {budget.logs} logs alarm "
             f"with the thresholds fitted on the others (the budget expects "
             f"{budget.per_log_rate * budget.logs:.1f}); {budget.in_sample_alarmed} reach the "
             "final thresholds"]
    width = max((len(f.judge.label) for f in budget.fits), default=0)
    for f in budget.fits:
        share = "" if f.share >= f.offered else f", share lowered to {f.share:.2%}"
        values = (f"{f.fit.logs} blocks of its logs (a log's share spread over "
                  f"{f.judge.blocks.per_log:.1f} blocks: {f.offered:.4%} each)"
                  if f.by_block and f.judge.blocks is not None else f"{f.fit.logs} logs")
        lines.append(f"    {f.judge.label:<{width}} threshold {f.threshold:.4g}  ({f.fit.law} "
                     f"fit to {values}; left out, {f.loo_alarms} alarm{share})")
    if budget.effort_rate is not None:
        lines.append(f"    effort shares: a budget of {budget.effort_rate:.2%} of logs")
    return lines


def _kept(mode: ModeCalibration, names: Sequence[str]) -> str:
    """The profile's thresholds a mode keeps for signals the replay does not judge."""
    values = sorted({mode.thresholds[name] for name in names})
    if len(names) == 1:
        return f"the profile's threshold {values[0]:g} % stays"
    return "the profile's thresholds stay (" + (f"{values[0]:g} %" if len(values) == 1 else
                                               ", ".join(f"{n} {mode.thresholds[n]:g} %"
                                                         for n in names)) + ")"


def calibration_lines(result: CalibrationResult) -> list[str]:
    lines = ([f"calibrated on {result.normal_hours:.2f} h of normal data, margin "
              f"{result.margin:g}; false alarms on those logs: 0 (rate < "
              f"{result.false_alarm_bound_per_hour:.2f} per hour, 95 % bound)"]
             if result.budget is None else budget_lines(result.budget, result.normal_hours))
    if result.modes:
        lines.append("  per mode, its samples of normal data; per judged signal, max g (the "
                     "largest residual index on these logs, % of full scale) -> its threshold, "
                     "set by the log whose peak it is (and how far that peak stands above the "
                     "next log's)")
    for mode in result.modes:
        kept = ("  (too little data: the profile's thresholds, raised where these logs "
                "need it)" if mode.kept_default else "")
        lines.append(f"  {mode.mode:<8} {mode.samples:>7} samples{kept}")
        for name, evidence in mode.evidence.items():
            ratio = evidence.dominance
            beside = ("" if evidence.next_peak is None or ratio is None
                      else f", {ratio:.2f}x the next log's {evidence.next_peak:g} %")
            lines.append(f"    {name:<12} max g {mode.max_g[name]:g} % -> threshold "
                         f"{mode.thresholds[name]:g} %  (set by {evidence.set_by}{beside})")
        lines += [f"    {who}: skipped, {why}; {_kept(mode, who.split(', '))}"
                  for who, why in by_reason(mode.skipped)]
    for check in result.faulty:
        named = check.component or " or ".join(check.candidates) or "no component named"
        lines.append(f"  faulty {check.log}: {check.verdict.upper()} ({named}); the largest g "
                     f"of a judged signal reached {check.peak_ratio:.2f}x its threshold "
                     "(1 or more alarms)")
    if result.relation_thresholds_raised:
        lines.append("  commands vs motion: extra effort allowed raised so that no calibration "
                     "log alarms: " + ", ".join(f"{k} {v:.0%}" for k, v in
                                                result.relation_thresholds_raised.items()))
    if result.start_thresholds_raised:
        lines.append("  start: how far a start may lie from the normal start raised so that no "
                     "calibration log alarms: " + ", ".join(result.start_thresholds_raised))
    if result.effort is not None:
        lines += effort_lines(result.effort)
        lines += [f"  left out: {note}" for note in result.effort_notes]
    lines += change_lines(result)
    lines += [f"warning: {warning}" for warning in result.warnings]
    return lines


def change_lines(result: CalibrationResult) -> list[str]:
    """What calibrate set for the change test: each statistic's thresholds, the signals
    judged only within signatures or too briefly to set any, and those for a log without
    an input."""
    lines = []
    also = (f" and the {len(result.change_trained_on)} trained on"
            if result.change_trained_on else "")
    for statistic, values in result.change.items():
        lines.append(f"  change test ({statistic}; each log against its own beginning): "
                     f"largest on these logs{also} -> threshold: " + ", ".join(
                         f"{name} {largest:g} -> {threshold:g}"
                         for name, (largest, threshold) in values.items()))
    lines += [f"  change test: {name} judged only within {' and '.join(within) or 'no signature'}"
              f", no threshold of its own ({why})"
              for name, (within, why) in result.change_within.items()]
    if result.change_too_little:
        lines.append("  change test: no thresholds (not judged) where these logs let it judge "
                     f"too briefly to set them (needs {MIN_JUDGED_S:.0f} s, all logs together; "
                     "add normal logs, or longer ones): " + ", ".join(
                         f"{name} {seconds:g} s" for name, seconds in
                         result.change_too_little.items()))
    for name, by_statistic in result.change_unfed.items():
        lines.append(f"  change test for a log without {name} (these logs replayed with it "
                     "held at its typical value), where higher: " + "; ".join(
                         f"{statistic} " + ", ".join(f"{signal} {value:g}"
                                                     for signal, value in values.items())
                         for statistic, values in by_statistic.items()))
    return lines
