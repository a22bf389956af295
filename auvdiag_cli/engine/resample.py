"""Put every signal on the model's Δt grid.

Method (documented for users in docs/method.md):
- the grid starts at the first instant every signal has been heard and ends at the last
  instant all of them are still heard, in steps of Δt;
- commands are held (zero-order hold): the value at grid time t is the last command
  received at or before t, since an actuator keeps its last command;
- sensors are averaged over the bin (t − Δt, t]: a faster sensor (the 50 Hz IMU) is low-pass
  filtered to the model rate; an empty bin takes the linear interpolation of its neighbours;
- before that, each series is sorted by time, exact duplicate timestamps keep the last value,
  and non-finite values, or values beyond ±1e12 (corrupted floats), are dropped (and
  counted);
- a silence longer than ``max_gap_s`` on any signal is a gap: grid points inside it are NaN
  (never interpolated across) and the gap is reported. A gap in a *command* means the
  actuators' history is unknown there: all sensors are NaN inside it and the model replay
  restarts from the measured state after it (``restarts``);
- measured inputs (the profile's ``[[inputs]]``: battery voltage, attitude) are averaged
  like sensors but drive the model like commands: a gap in one is treated as a command gap;
  one the log lacks altogether (`LogSources.optional`) reads 0 throughout, as a channel
  nothing fed (`ingest` holds it at its typical value);
- actuator outputs (the profile's ``[[outputs]]``, read for the effort check only) are
  held like commands but drive nothing and set neither the grid nor the gaps of the
  others: they are NaN inside their own gaps, before they are first heard, long after they
  are last heard, and throughout where the log lacks them;
- where the profile names an operating flag (armed, under way), time when it is clear is
  treated like a command gap: sensors NaN, never judged or trained on, and the replay
  restarts from the measured state when operation begins again;
- a clock that jumps back by more than ``max_gap_s`` in the order the log stored the
  samples (a clock reset) is re-timed: the samples after the jump are shifted to follow on
  one median period after the last sample before it, and the jump is reported;
- a stretch longer than `silences.LONG_S` with nothing to judge (no signal at all, no
  command, or not operating) keeps only its edges on the grid (`silences`).
"""

from dataclasses import dataclass, field, replace

import numpy as np

from adapters.signals import OPERATING, Series, Signals
from adapters.timebase import MAX_TIME_NS
from auvdiag_cli.engine.silences import LONG_S, kept_steps, lattice_spans, silences

NS_PER_S = 1_000_000_000
# The grid is sized from the times; times can be damaged. A grid far longer than the
# samples could fill means a broken clock, and is refused rather than allocated.
GRID_STEPS_PER_SAMPLE = 10
MIN_GRID_LIMIT = 1_000_000
# No quantity a vehicle logs reaches this in SI units; a float whose exponent bits were
# corrupted does (1e300 is one flipped bit away from 1.0).
MAX_ABS_VALUE = 1e12
# A command logged at less than 1 / (factor · Δt) is flagged: the zero-order hold then
# spans more than this many model steps.
SLOW_COMMAND_FACTOR = 1.5
# A command within this of 0 (normalised, −1 … 1) is neutral: the actuator is idle.
NEUTRAL_COMMAND = 1e-3


@dataclass(frozen=True)
class Gap:
    signal: str
    start_s: float
    end_s: float


@dataclass
class AlignedFrame:
    """Signals on a common grid; ``time_s`` counts from the log's first message."""

    time_s: np.ndarray
    commands: np.ndarray        # (steps, n_commands)
    sensors: np.ndarray         # (steps, n_sensors), NaN inside gaps
    command_names: tuple[str, ...]
    sensor_names: tuple[str, ...]
    dt_s: float
    gaps: list[Gap] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    restarts: list[int] = field(default_factory=list)   # grid indices where replay restarts
    slow_commands: list[str] = field(default_factory=list)   # also in notes
    operating: np.ndarray = field(default_factory=lambda: np.ones(0, bool))
    inputs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (steps, n_inputs)
    input_names: tuple[str, ...] = ()
    not_operating_s: float = 0.0        # time on the grid the vehicle was not operating
    flat: dict[str, str] = field(default_factory=dict)   # sensor -> what it reads throughout
    flat_inputs: dict[str, str] = field(default_factory=dict)   # the same of the inputs
    # Actuator outputs read for the effort check only, held; NaN in gaps and where absent.
    outputs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (steps, n_outputs)
    output_names: tuple[str, ...] = ()

    def sensor(self, name: str) -> np.ndarray:
        return self.sensors[:, self.sensor_names.index(name)]

    @property
    def drive(self) -> np.ndarray:
        """What the model is driven by: the commands, then the measured inputs."""
        return self.drive_with(self.commands)

    def drive_with(self, commands: np.ndarray) -> np.ndarray:
        """`drive`, with other commands (a fault assumed) and this log's measured inputs."""
        return np.hstack([commands, self.inputs]) if self.input_names else commands

    @property
    def efforts(self) -> np.ndarray:
        """What the effort check reads: the commands, then the actuator outputs."""
        return np.hstack([self.commands, self.outputs]) if self.output_names else self.commands


def _unjump(series: Series, name: str, max_gap_ns: int, start_ns: int, notes: list[str]
            ) -> Series:
    times = series.times_ns.astype(np.int64, copy=True)
    steps = np.diff(times)
    jumps = np.flatnonzero(steps < -max_gap_ns)
    if jumps.size == 0:
        return series
    period = int(np.median(steps[steps > 0])) if (steps > 0).any() else 0
    for i in jumps:
        back = int(times[i]) - int(times[i + 1])
        if int(times[i + 1:].max()) + back + period >= MAX_TIME_NS:
            raise ValueError(f"{name}: the clock jumps back by {back / NS_PER_S:.3g} s, "
                             "further than any log could run: its timestamps are damaged")
        times[i + 1:] += back + period
        notes.append(f"{name}: clock jumps back by {back / NS_PER_S:.1f} s at "
                     f"{(times[i] - start_ns) / NS_PER_S:.1f} s; later samples re-timed")
    return Series(times, series.values, series.name)


def _clean(series: Series, name: str, max_gap_ns: int, start_ns: int, notes: list[str]
           ) -> Series:
    with np.errstate(invalid="ignore"):
        usable = np.isfinite(series.values) & (np.abs(series.values) < MAX_ABS_VALUE)
    if not usable.all():
        notes.append(f"{name}: dropped {int((~usable).sum())} non-finite or impossible "
                     "value(s)")
        series = series.where(usable)
    series = _unjump(series, name, max_gap_ns, start_ns, notes)
    if (np.diff(series.times_ns) < 0).any():
        notes.append(f"{name}: messages out of time order, sorted")
        series = series.where(np.argsort(series.times_ns, kind="stable"))
    duplicated = np.concatenate((series.times_ns[1:] == series.times_ns[:-1], [False]))
    if duplicated.any():
        notes.append(f"{name}: {int(duplicated.sum())} duplicate timestamp(s), kept the last")
        series = series.where(~duplicated)
    return series


def slow_command_note(rates_hz: dict[str, float | None], dt_s: float) -> str | None:
    """A warning when commands are logged more slowly than the model steps: the replay then
    holds each command over several steps, a coarser history than the model learnt from
    (ground stations often log actuator outputs at 2-4 Hz)."""
    slow = {name: rate for name, rate in rates_hz.items()
            if rate is not None and rate * dt_s * SLOW_COMMAND_FACTOR < 1.0}
    if not slow:
        return None
    lowest = min(slow.values())
    rates = f"{lowest:.1f} Hz" if max(slow.values()) - lowest < 0.05 else \
        f"{lowest:.1f}-{max(slow.values()):.1f} Hz"
    return (f"{', '.join(slow)} {'is' if len(slow) == 1 else 'are'} logged at {rates}, below "
            f"the model's {1 / dt_s:g} Hz step: each command is held about "
            f"{1 / lowest:.2f} s, so changes faster than that are invisible to the replay and "
            "residuals after them are larger (raise the logging rate: ArduPilot streams "
            "SERVO_OUTPUT_RAW at SRn_RC_CHAN Hz, NAV_CONTROLLER_OUTPUT at SRn_EXT_STAT Hz on "
            "telemetry link n)")


def _rate_hz(times_ns: np.ndarray) -> float | None:
    """Messages a second, from the median spacing (gaps do not lower it)."""
    steps = np.diff(times_ns)
    steps = steps[steps > 0]
    return NS_PER_S / float(np.median(steps)) if steps.size else None


def _commanded(commands: np.ndarray, idle_steps: int) -> np.ndarray:
    """Operating by command activity: some command was off neutral within the last
    ``idle_steps`` steps (a log without an armed flag: idle on deck is not a dive)."""
    active = (np.abs(np.nan_to_num(commands)) > NEUTRAL_COMMAND).any(axis=1)
    steps = np.arange(active.size)
    last_active = np.maximum.accumulate(np.where(active, steps, -1))
    return (last_active >= 0) & (steps - last_active < idle_steps)


def _operating(signals: Signals, grid_ns: np.ndarray) -> np.ndarray:
    """Where the vehicle operates, from the profile's operating flag (held from each
    message to the next; not operating before the first). No flag: everywhere."""
    flag = signals.series.get(OPERATING)
    if flag is None:
        return np.ones(grid_ns.size, bool)
    flag = flag.where(np.isfinite(flag.values))
    flag = flag.where(np.argsort(flag.times_ns, kind="stable"))
    if not len(flag):
        raise ValueError("the operating flag has no usable value")
    index = np.searchsorted(flag.times_ns, grid_ns, side="right") - 1
    return (index >= 0) & (flag.values[np.clip(index, 0, None)] != 0)


class NeverOperates(ValueError):
    """The operating flag or the commands say the vehicle never operated."""


def _note_operating(operating: np.ndarray, dt_s: float, notes: list[str]) -> None:
    if not operating.any():
        raise NeverOperates("the vehicle never operates in this log (never armed, or its commands "
                         "never leave neutral): there is nothing to judge")
    if not operating.all():
        stretches = int(operating[0]) + int((~operating[:-1] & operating[1:]).sum())
        notes.append(f"not operating (disarmed or idle) for {(~operating).sum() * dt_s:.1f} s "
                     f"of {operating.size * dt_s:.1f} s: that time is neither judged nor "
                     f"trained on; {stretches} operating stretch(es), each replayed from its "
                     "own start")


def _gaps(times_ns: np.ndarray, max_gap_ns: int) -> list[tuple[int, int]]:
    steps = np.diff(times_ns)
    return [(int(times_ns[i]), int(times_ns[i + 1])) for i in np.flatnonzero(steps > max_gap_ns)]


def _held(times_ns: np.ndarray, values: np.ndarray, grid_ns: np.ndarray) -> np.ndarray:
    index = np.searchsorted(times_ns, grid_ns, side="right") - 1
    return values[np.clip(index, 0, None)]


def _held_output(times_ns: np.ndarray, values: np.ndarray, grid_ns: np.ndarray,
                 max_gap_ns: int) -> np.ndarray:
    """An output held, unknown (NaN) before it is first heard and long after it is last."""
    held = _held(times_ns, values, grid_ns)
    held[(grid_ns < times_ns[0]) | (grid_ns > times_ns[-1] + max_gap_ns)] = np.nan
    return held


def _bin_mean(times_ns: np.ndarray, values: np.ndarray, grid_ns: np.ndarray, dt_ns: int
              ) -> np.ndarray:
    right = np.searchsorted(times_ns, grid_ns, side="right")
    left = np.searchsorted(times_ns, grid_ns - dt_ns, side="right")
    sums = np.concatenate(([0.0], np.cumsum(values)))
    counts = right - left
    with np.errstate(invalid="ignore", divide="ignore"):
        means = (sums[right] - sums[left]) / counts
    empty = counts == 0
    if empty.any():
        means[empty] = np.interp(grid_ns[empty], times_ns, values)
    return means


def _grid(cleaned: dict[str, Series], dt_ns: int) -> np.ndarray:
    """The Δt grid over the time every signal covers, less the inside of long silences
    (`silences`); damaged timestamps refused."""
    first_ns = max(int(s.times_ns[0]) for s in cleaned.values())
    last_ns = min(int(s.times_ns[-1]) for s in cleaned.values())
    if last_ns - first_ns < 2 * dt_ns:
        raise ValueError("the signals overlap for less than two model steps")
    quiet = silences(s.times_ns for s in cleaned.values())
    spans = lattice_spans(first_ns, last_ns, dt_ns, quiet)
    most = max(len(s) for s in cleaned.values())
    if sum(stop - start for start, stop in spans) > max(GRID_STEPS_PER_SAMPLE * most,
                                                        MIN_GRID_LIMIT):
        raise ValueError(f"the signals span {(last_ns - first_ns) / NS_PER_S:.3g} s but hold "
                         f"at most {most} samples each: the timestamps are damaged")
    return first_ns + dt_ns * np.concatenate([np.arange(start, stop, dtype=np.int64)
                                              for start, stop in spans])


def _operating_steps(signals: Signals, grid_ns: np.ndarray, commands: np.ndarray,
                     dt_s: float, idle_after_s: float | None, notes: list[str]) -> np.ndarray:
    """Where the vehicle operates: the profile's flag, and commanded within the idle limit."""
    operating = _operating(signals, grid_ns)
    if idle_after_s is not None:
        operating &= _commanded(commands, round(idle_after_s / dt_s))
    # A sample averages the step before it: the first step of a stretch still holds
    # readings from before it, so operation counts from the second.
    operating &= np.concatenate(([operating[0]], operating[:-1]))
    _note_operating(operating, dt_s, notes)
    return operating


def _cleaned(signals: Signals, required: tuple[str, ...], optional: tuple[str, ...],
             output_names: tuple[str, ...], max_gap_ns: int, notes: list[str]
             ) -> dict[str, Series]:
    """Each signal cleaned: one without a usable sample refused, but an ``optional`` one
    (a measured input, an output) the log lacks left out, and an output without a usable
    sample too."""
    cleaned = {name: _clean(signals.series[name], name, max_gap_ns, signals.start_ns, notes)
               for name in required + optional if name in signals.series or name in required}
    cleaned = {n: c for n, c in cleaned.items() if len(c) or n not in output_names}
    empty = [name for name, series in cleaned.items() if not len(series)]
    if empty:
        raise ValueError(f"no usable samples for {', '.join(empty)}")
    return cleaned


def resample(signals: Signals, command_names: tuple[str, ...], sensor_names: tuple[str, ...],
             dt_s: float, max_gap_s: float = 1.0, idle_after_s: float | None = None,
             input_names: tuple[str, ...] = (), output_names: tuple[str, ...] = ()
             ) -> AlignedFrame:
    """Align ``signals`` on a Δt grid as described in the module docstring."""
    notes: list[str] = []
    max_gap_ns = round(max_gap_s * NS_PER_S)
    cleaned = _cleaned(signals, command_names + sensor_names, input_names + output_names,
                       output_names, max_gap_ns, notes)
    drives = command_names + input_names
    dt_ns = round(dt_s * NS_PER_S)
    grid_ns = _grid({n: c for n, c in cleaned.items() if n not in output_names}, dt_ns)
    gaps: list[Gap] = []
    columns: dict[str, np.ndarray] = {}
    blind = np.zeros(len(grid_ns), dtype=bool)     # inside a command gap
    command_rates: dict[str, float | None] = {}
    restarts: set[int] = set()
    for name, series in cleaned.items():
        times_ns, values = series.times_ns, series.values.astype(np.float64, copy=False)
        if name in command_names:
            columns[name] = _held(times_ns, values, grid_ns)
            command_rates[name] = _rate_hz(times_ns)
        elif name in output_names:
            columns[name] = _held_output(times_ns, values, grid_ns, max_gap_ns)
        else:
            columns[name] = _bin_mean(times_ns, values, grid_ns, dt_ns)
        for start_ns, end_ns in _gaps(times_ns, max_gap_ns):
            inside = (grid_ns > start_ns) & (grid_ns < end_ns)
            if name in drives:
                blind |= inside
                restarts.add(int(np.searchsorted(grid_ns, end_ns)))
            else:
                columns[name][inside] = np.nan
            gaps.append(Gap(name, (start_ns - signals.start_ns) / NS_PER_S,
                            (end_ns - signals.start_ns) / NS_PER_S))
    slow_commands = [n for n in [slow_command_note(command_rates, dt_s)] if n is not None]
    commands = np.column_stack([columns[n] for n in command_names])
    operating = _operating_steps(signals, grid_ns, commands, dt_s, idle_after_s, notes)
    blind |= ~operating
    restarts.update(int(i) + 1 for i in np.flatnonzero(~operating[:-1] & operating[1:]))
    sensors = np.column_stack([columns[n] for n in sensor_names])
    sensors[blind] = np.nan
    return _without_long_blind_runs(AlignedFrame(
        time_s=(grid_ns - signals.start_ns) / NS_PER_S,
        commands=commands,
        sensors=sensors,
        command_names=command_names,
        sensor_names=sensor_names,
        dt_s=dt_s,
        gaps=gaps,
        notes=notes + slow_commands,
        slow_commands=slow_commands,
        restarts=sorted(r for r in restarts if 0 < r < len(grid_ns)),
        operating=operating,
        inputs=_stacked(columns, input_names, len(grid_ns), 0.0),
        input_names=input_names,
        outputs=_stacked(columns, output_names, len(grid_ns), np.nan),
        output_names=output_names,
        not_operating_s=float((~operating).sum()) * dt_s,
    ), blind, grid_ns)


def _stacked(columns: dict[str, np.ndarray], names: tuple[str, ...], steps: int,
             absent: float) -> np.ndarray:
    """(steps, len(names)) of these columns, ``absent`` for one the log lacks."""
    return np.array([columns.get(n, np.full(steps, absent)) for n in names],
                    float).reshape(len(names), steps).T


def _without_long_blind_runs(frame: AlignedFrame, blind: np.ndarray, grid_ns: np.ndarray
                             ) -> AlignedFrame:
    """The frame less the inside of each long stretch where nothing can be judged
    (`silences.kept_steps`); a replay restart inside one moves to the next step kept."""
    keep = kept_steps(blind, grid_ns)
    kept = np.flatnonzero(keep)
    left_off = float(grid_ns[-1] - grid_ns[0]) / NS_PER_S - (kept.size - 1) * frame.dt_s
    if left_off < frame.dt_s:
        return frame
    restarts = sorted({int(np.searchsorted(kept, r)) for r in frame.restarts} - {0, kept.size})
    note = (f"{left_off:.0f} s with nothing to judge (no signal, no command or not operating "
            f"for more than {LONG_S:.0f} s at a time) left off the model grid; the replay "
            "restarts after each such stretch")
    return replace(frame, time_s=frame.time_s[keep], commands=frame.commands[keep],
                   sensors=frame.sensors[keep], operating=frame.operating[keep],
                   inputs=frame.inputs[keep], outputs=frame.outputs[keep], restarts=restarts,
                   notes=[*frame.notes, note])
