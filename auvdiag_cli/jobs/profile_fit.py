"""Which shipped profiles a log fits: every signal's topic (or its fallback's) is in the log,
with the field the profile reads where the log lists its fields."""

from pathlib import Path

from adapters import inventory
from adapters.collect import MISSING_SIGNALS
from adapters.inventory import TopicInfo
from adapters.signals import FieldSource
from auvdiag_cli.vehicle.profile import builtin_profiles, load_profile
from auvdiag_errors import AuvdiagError, LogError

# How the readers say that a log lacks what a profile names.
MISSING = (MISSING_SIGNALS, "missing topic(s)", "no column(s)")


def _offers(topics: dict[str, TopicInfo], source: FieldSource) -> bool:
    topic = topics.get(source.topic)
    if topic is None:
        return False
    named = dict(source.where).get("name")      # NAMED_VALUE_FLOAT and its kind
    if named is not None and topic.names and named not in topic.names:
        return False
    return not topic.fields or source.field in topic.fields or source.topic == source.field


def profiles_that_fit(path: Path, besides: str = "") -> list[str]:
    """The built-in profiles whose signals all resolve on the log at ``path`` (none when it
    cannot be inventoried), but the vehicle named ``besides``."""
    try:
        contents, family = inventory(path)
    except AuvdiagError:
        return []
    topics = {topic.name: topic for topic in contents.topics}
    fitting = []
    for name in builtin_profiles():
        profile = load_profile(Path(name))
        sources = profile.sources.get(family)
        if profile.name != besides and sources is not None and all(
                _offers(topics, source) or (signal in sources.fallbacks
                                            and _offers(topics, sources.fallbacks[signal]))
                for signal, source in sources.signals.items()):
            fitting.append(name)
    return fitting


def with_profile_hint(error: LogError, profile: str) -> LogError:
    """``error``, where it says that a signal the profile ``profile`` names is not in the
    log, with the shipped profiles that do fit the log named (where any does)."""
    if not error.problem.startswith(MISSING):
        return error
    fitting = profiles_that_fit(error.path, besides=profile)
    if not fitting:
        return error
    return LogError(error.path, f"{error.problem} (profile {profile}); the shipped profiles "
                                f"that fit this log: {', '.join(fitting)} (--profile NAME)")
