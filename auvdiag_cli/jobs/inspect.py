"""`auvdiag inspect`: what a log holds and which of the profile's signals it provides."""

import difflib
from dataclasses import dataclass, field, replace
from pathlib import Path

from adapters import (
    FieldSource,
    LogInventory,
    LogSources,
    Signals,
    inventory,
    read_log,
    with_ros_words,
)
from adapters.autopilot_setup import AutopilotSetup, autopilot_setup
from adapters.signals import CLOCK_REFERENCE
from auvdiag_cli.engine.log_clock import clock_gap, utc_offset_ns
from auvdiag_cli.engine.resample import slow_command_note
from auvdiag_cli.vehicle.profile import Profile
from auvdiag_errors import LogError


@dataclass(frozen=True)
class SignalResolution:
    name: str
    topic: str
    field: str
    count: int
    rate_hz: float | None
    problem: str | None
    candidates: tuple[str, ...] = ()
    on_grid: str = ""            # how the signal is put on the model's step
    optional: bool = False       # a measured input: where absent, held at its typical value

    @property
    def resolved(self) -> bool:
        return self.problem is None


@dataclass
class Inspection:
    path: Path
    family: str
    inventory: LogInventory
    signals: list[SignalResolution]
    markers: list[str]
    mapped: bool = True          # False: the profile says nothing about this format family
    warnings: list[str] = field(default_factory=list)
    checked: bool = True         # False: no profile given, the log described only
    # What an ArduPilot log says of the vehicle that wrote it; None: nothing.
    autopilot: AutopilotSetup | None = None

    @property
    def usable(self) -> bool:
        """Every signal the diagnosis needs resolves in this log (True where no profile
        was given: there is nothing to miss)."""
        return not self.checked or (self.mapped and all(s.resolved or s.optional
                                                        for s in self.signals))


def on_grid(name: str, rate_hz: float | None, profile: Profile) -> str:
    """How resampling puts the signal on the model's step (see `engine.resample`)."""
    step = f"{profile.dt_s:g} s step"
    if name in profile.command_names:
        return f"held: the last command at each {step}"
    if name in profile.output_names:
        readers = [f"the loop {loop.name}" for loop in profile.tracking if name in loop.drive]
        if any(name in group.members for group in profile.effort_groups):
            readers.insert(0, "the effort check")
        read = " and ".join(readers) or "nothing (no effort group or loop names it)"
        return f"held: the last output at each {step}, read for {read} only"
    if name == CLOCK_REFERENCE:
        return "the UTC time the log carries: where its clock is off, it dates the log"
    if name not in profile.sensor_names + profile.input_names:
        return "a flag: the last value holds"
    per_step = (rate_hz or 0.0) * profile.dt_s
    if name in profile.input_names:
        return f"a measured input of the model, averaged over each {step}"
    if per_step >= 1.5:
        return f"averaged over each {step} (about {per_step:.0f} samples, anti-aliased)"
    if per_step < 0.9:
        return f"interpolated across {step}s without a sample"
    return f"about one sample a {step}"


def _closest(name: str, choices: list[str]) -> tuple[str, ...]:
    return tuple(difflib.get_close_matches(name, choices, n=3, cutoff=0.3))


def _guessed_span(path: Path, contents: LogInventory) -> tuple[LogInventory, str | None]:
    """A CSV whose clock the profile does not map: the column named like a clock, read in
    the unit its values suggest (as init-profile guesses it)."""
    from auvdiag_cli.jobs.profile_draft import guess_time_column

    try:
        time = guess_time_column(contents, path)
        if time is None:
            return contents, "no column is named like a clock: the span is unknown"
        clock = read_log(path, {"csv": LogSources({time.column: FieldSource(
            time.column, time.column)}, time=time)})
    except (LogError, ValueError):
        return contents, None
    return (replace(contents, start_ns=clock.start_ns, end_ns=clock.end_ns),
            f"clock: column {time.column} read in {time.unit} (guessed; the profile does not "
            "map this log's clock)")


def _described_only(path: Path, family: str, contents: LogInventory,
                    setup: AutopilotSetup | None) -> Inspection:
    """The log without a profile: a CSV's span from its column named like a clock."""
    note = None
    if contents.start_ns is None and family == "csv":
        contents, note = _guessed_span(path, contents)
    return Inspection(path, family, contents, [], [], mapped=False, checked=False,
                      warnings=[] if note is None else [note], autopilot=setup)


def _read_each(path: Path, family: str, sources: LogSources
               ) -> tuple[dict[str, Signals], dict[str, str]]:
    """(signal -> what read it, signal -> the problem that stopped it): one pass for all
    signals; on a failure, one for those that read, and one for each that does not, for
    the problem that names it."""
    if not sources.signals:
        return {}, {}
    try:
        everything = read_log(path, {family: sources})
        return {name: everything for name in sources.signals}, {}
    except LogError:
        pass
    try:
        tried = read_log(path, {family: replace(
            sources, optional=frozenset(sources.signals), tentative=True)})
        read = {name: tried for name in sources.signals if name in tried.series}
    except LogError:
        read = {}
    problems: dict[str, str] = {}
    for name, source in sources.signals.items():
        try:
            if name not in read:
                read[name] = read_log(path, {family: replace(
                    sources, signals={name: source}, segment=None)})
        except LogError as error:
            problems[name] = error.problem
    return read, problems


def inspect_log(path: Path, profile: Profile | None) -> Inspection:
    """Inventory the log, then read each of the profile's signals that its topics offer
    (None: describe the log only, its span from a column named like a clock for a CSV)."""
    contents, family = inventory(path)
    if family == "ros":
        contents = with_ros_words(path, contents)
    setup = autopilot_setup(path, family)
    if profile is None:
        return _described_only(path, family, contents, setup)
    sources = profile.sources.get(family)
    if sources is None:
        return Inspection(path, family, contents, [], [], mapped=False, autopilot=setup)
    available = {topic.name for topic in contents.topics}
    # A signal whose own topic is absent is read from its fallback where the log has that.
    shown = {n: s if s.topic in available or n not in sources.fallbacks
             else sources.fallbacks[n] for n, s in sources.signals.items()}
    present = {n: s for n, s in sources.signals.items() if shown[n].topic in available}
    read, problems = _read_each(path, family, replace(sources, signals=present))
    results = []
    for name, source in shown.items():
        series = read[name].series.get(name) if name in read else None
        optional = name in sources.optional
        if series is not None:
            span_s = (int(series.times_ns.max()) - int(series.times_ns.min())) / 1e9
            rate = (len(series) - 1) / span_s if span_s > 0 else None
            results.append(SignalResolution(name, source.topic, source.said, len(series),
                                            rate, None, on_grid=on_grid(name, rate, profile)))
        elif name in problems or source.topic in available:
            results.append(SignalResolution(name, source.topic, source.said, 0, None,
                                            problems.get(name, "no samples in the log"),
                                            optional=optional))
        else:
            results.append(SignalResolution(name, source.topic, source.said, 0, None,
                                            f"no {source.topic} in the log",
                                            _closest(source.topic, sorted(available)),
                                            optional=optional))
    first = next(iter(read.values()), None)
    if contents.start_ns is None and first is not None:     # a CSV: its clock is a column
        contents = replace(contents, start_ns=first.start_ns, end_ns=first.end_ns)
    contents, clock_note = _guessed_span(path, contents) if (
        contents.start_ns is None and family == "csv") else (contents, None)
    markers = [m.label for m in first.markers] if first is not None else []
    slow = slow_command_note({s.name: s.rate_hz for s in results
                              if s.name in profile.command_names}, profile.dt_s)
    warnings = [note for note in (clock_note, slow) if note is not None]
    return Inspection(path, family, contents, results, markers,
                      warnings=warnings + _clock_off(read), autopilot=setup)


def _clock_off(read: dict[str, Signals]) -> list[str]:
    """A log whose clock is off from the UTC time it carries, said beside its span."""
    gap = clock_gap(utc_offset_ns(read[CLOCK_REFERENCE]) if CLOCK_REFERENCE in read else 0)
    return [] if gap is None else [f"{gap}: diagnose and audit date it by that time; the span "
                                   "above is on the log's own clock, as --healthy takes it"]
