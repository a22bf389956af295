"""A simulated dive as one time-ordered stream of messages, laid out the way the profile says
the vehicle logs them (its `[sources.FAMILY]` table read backwards), whatever the format."""

from collections.abc import Iterator
from dataclasses import dataclass

from adapters.signals import OPERATING, FieldSource, LogSources
from auvdiag_cli.simulator.run import SimulatedDive, Stream
from auvdiag_cli.vehicle.profile import Profile

STATE_PERIOD_NS = 1_000_000_000      # a vehicle's state is published once a second
# A text an operating flag's map does not list, written where every such text means it.
UNLISTED_TEXT = "OPERATING"


@dataclass(frozen=True)
class Record:
    """One message: its receive time (the log's clock), topic or message name, the raw value
    of each field path it carries (the profile's scale and offset undone), the fields a
    reader matches on (``where``), or for a segment marker its text."""

    time_ns: int
    topic: str
    fields: tuple[tuple[str, float | str], ...] = ()
    where: tuple[tuple[str, str], ...] = ()
    text: tuple[str, str] | None = None        # (field, text) of a segment marker


def raw_value(source: FieldSource, value: float) -> float:
    return (value - source.offset) / source.scale


def operating_raw(source: FieldSource) -> float | str:
    """The raw value that says "operating" to the profile's operating source: its bit, the
    listed value that means it, a value the map does not list where those mean it (`"*"`),
    else 1."""
    listed = next((raw for raw, meaning in source.values if meaning), None)
    if source.bits or (listed is None and not source.otherwise):
        return float(source.bits or 1)
    if listed is not None:
        return listed if isinstance(listed, str) else float(listed)
    keys = [raw for raw, _ in source.values]
    if any(isinstance(key, str) for key in keys):
        return UNLISTED_TEXT
    return float(max((key for key in keys if isinstance(key, int)), default=0) + 1)


def operating_records(dive: SimulatedDive, profile: Profile, family: str) -> list[Record]:
    """The flag the profile's operating source reads (mavros's state: armed; PX4's
    actuator_armed), once a second over the dive, as those are published: operating
    throughout."""
    source = family_sources(profile, family).signals.get(OPERATING)
    if source is None:
        return []
    raw = operating_raw(source)
    return [Record(dive.start_ns + k * STATE_PERIOD_NS, source.topic, ((source.field, raw),),
                   source.where)
            for k in range(int(dive.duration_s) + 1)]


def family_sources(profile: Profile, family: str) -> LogSources:
    sources = profile.sources.get(family)
    if sources is None:
        raise ValueError(f"profile {profile.name!r} has no [sources.{family}] table: it does "
                         f"not say how the vehicle logs {family} messages")
    angles = [name for name, source in sources.signals.items() if source.angle]
    if angles:
        raise ValueError(f"profile {profile.name!r} reads {', '.join(angles)} from a "
                         f"quaternion in its [sources.{family}] table: the simulator writes "
                         "each signal as a field of its own, not as a quaternion")
    return sources


def _groups(sources: LogSources, names: tuple[str, ...]
            ) -> dict[tuple[str, tuple[tuple[str, str], ...]], list[str]]:
    """Signals that travel in one message: same topic, same ``where``."""
    groups: dict[tuple[str, tuple[tuple[str, str], ...]], list[str]] = {}
    for name in names:
        source = sources.signals[name]
        groups.setdefault((source.topic, source.where), []).append(name)
    return groups


def _stream_records(start_ns: int, sources: LogSources, topic: str,
                    where: tuple[tuple[str, str], ...], names: list[str],
                    columns: list[list[float]], times_s: list[float]) -> list[Record]:
    paths = [sources.signals[name].field for name in names]
    return [Record(start_ns + round(t * 1e9), topic,
                   tuple((path, raw_value(sources.signals[name], column[k]))
                         for path, name, column in zip(paths, names, columns, strict=True)),
                   where)
            for k, t in enumerate(times_s)]


def dive_records(dive: SimulatedDive, profile: Profile, family: str) -> Iterator[Record]:
    """Every message of the dive in receive-time order."""
    sources = family_sources(profile, family)
    records: list[Record] = []
    command_columns = [list(c) for c in zip(*dive.commands.values, strict=True)]
    for (topic, where), names in _groups(sources, profile.command_names).items():
        columns = [command_columns[profile.command_names.index(n)] for n in names]
        records += _stream_records(dive.start_ns, sources, topic, where, names, columns,
                                   dive.commands.times_s)
    for (topic, where), names in _groups(sources, profile.sensor_names).items():
        streams: list[Stream] = [dive.sensors[n] for n in names]
        if len({len(s.times_s) for s in streams}) > 1:
            raise ValueError(f"sensors {', '.join(names)} share {topic} but the simulation "
                             "samples them at different rates")
        columns = [[v[0] for v in s.values] for s in streams]
        records += _stream_records(dive.start_ns, sources, topic, where, names, columns,
                                   streams[0].times_s)
    segment = sources.segment
    if segment is not None:
        records += [Record(dive.start_ns + round(t * 1e9), segment.topic,
                           text=(segment.field, segment.prefix + label))
                    for t, label in dive.markers]
    records.sort(key=lambda record: record.time_ns)
    yield from records


def first_message_s(dive: SimulatedDive) -> float:
    """Seconds from the dive's clock start to its first message (receive jitter)."""
    streams = [dive.commands, *dive.sensors.values()]
    return min([min(s.times_s) for s in streams if s.times_s] + [t for t, _ in dive.markers])
