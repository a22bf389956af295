"""ROS namespaces: a vehicle launched under ``/rov2`` publishes the profile's
``/mavros/rc/out`` as ``/rov2/mavros/rc/out``. The namespace is found from the log's topics
(the one under which most of the profile's topics are, when more than at the root), or
named in the profile; it then says which vehicle wrote the log."""

from collections import Counter
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from pathlib import Path

from auvdiag_errors import LogError

ROOT = ""


def normalised(namespace: str) -> str:
    """``rov2``, ``/rov2/`` and ``/rov2`` are one namespace; ``/`` and ``""`` the root."""
    parts = [part for part in namespace.split("/") if part]
    return "/" + "/".join(parts) if parts else ROOT


def under(namespace: str, topic: str) -> str:
    """The topic as a node in ``namespace`` publishes it (a relative topic name resolved)."""
    return f"{namespace}/{topic.lstrip('/')}" if namespace else topic


@dataclass(frozen=True)
class Resolution:
    namespace: str                     # ROOT: the topics as the profile names them
    names: dict[str, str]              # profile topic → the log's topic


def resolve(path: Path, wanted: Collection[str], available: Iterable[str],
            namespace: str | None = None) -> Resolution:
    """Where the profile's topics ``wanted`` are among the log's topics ``available``.

    ``namespace`` None: found from the topics: the root, unless some namespace holds more
    of the profile's topics than the root does; two namespaces holding equally many (two
    vehicles in one log) are an error, naming them. A topic the namespace lacks
    is looked for at the root (``/tf``, ``/rosout`` are global)."""
    log_topics = set(available)
    if namespace is None:
        namespace = _found_namespace(path, wanted, log_topics)
    namespace = normalised(namespace)
    names = {topic: under(namespace, topic) if under(namespace, topic) in log_topics
             else topic for topic in wanted}
    return Resolution(namespace, names)


def naming_hint(namespace: str) -> str:
    """How a user picks the namespace to read."""
    return f"name it with namespace = \"{namespace or '/'}\" under [sources.ros] in the profile"


def _found_namespace(path: Path, wanted: Collection[str], log_topics: set[str]) -> str:
    at_root = sum(topic in log_topics for topic in wanted)
    if at_root == len(wanted):
        return ROOT
    held: Counter[str] = Counter()
    for topic in log_topics:
        for profile_topic in wanted:
            suffix = "/" + profile_topic.lstrip("/")
            if topic.endswith(suffix) and len(topic) > len(suffix):
                held[normalised(topic[:-len(suffix)])] += 1
    most = max(held.values(), default=0)
    if most <= at_root:
        return ROOT
    best = sorted(ns for ns, count in held.items() if count == most)
    if len(best) > 1:
        raise LogError(path, f"the profile's topics are under {len(best)} namespaces "
                             f"({', '.join(best)}): the log holds several vehicles; "
                             + naming_hint(best[0]))
    return best[0]
