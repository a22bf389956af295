"""ROS 2 bags in sqlite3 storage (``.db3``, one file or a bag split over several) read with
one SQL query per file for the wanted topics, the message blobs handed over in bulk and
their fields read column-wise, instead of one Python object per message.

Message definitions come from the bag's ``message_definitions`` table (Iron and later);
types it does not define (Humble and older write none) come from ROS 2 Humble's."""

import sqlite3
from collections.abc import Iterable
from contextlib import closing
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from adapters.collect import SignalCollector
from adapters.fieldnames import ros_field_paths
from adapters.inventory import LogInventory, TopicInfo
from adapters.limits import MAX_CHUNK_BYTES
from adapters.ros_columns import TopicBatches
from adapters.signals import Signals
from auvdiag_errors import LogError

ROWS_AT_ONCE = 20_000          # rows fetched per round trip: bounds memory on long bags
# sqlite reports a damaged record that declares more bytes than it will allocate as "out of
# memory", which Python raises as MemoryError; an error message quoting a damaged schema
# is not UTF-8, which Python raises as UnicodeDecodeError. From a query, both are damage.
SQLITE_FAILURES = (sqlite3.Error, MemoryError, UnicodeDecodeError)
IDL_SEPARATOR = "=" * 80 + "\n"


def _connect(storage: Path) -> sqlite3.Connection:
    db = sqlite3.connect(f"file:{quote(str(storage.resolve()))}?mode=ro", uri=True)
    # A damaged record can declare a blob of a gigabyte: refuse it rather than allocate it.
    db.setlimit(sqlite3.SQLITE_LIMIT_LENGTH, MAX_CHUNK_BYTES)
    # Damaged text (a topic name, a definition) is not UTF-8: keep it readable, not fatal.
    db.text_factory = lambda raw: raw.decode("utf-8", "replace")
    return db


def _problem(error: BaseException) -> str:
    return str(error).strip() or type(error).__name__


def db3_topics(storages: list[Path]) -> set[str] | None:
    """The topics of a db3 bag from its topics tables alone; None where one is unreadable."""
    names: set[str] = set()
    try:
        for storage in storages:
            with closing(_connect(storage)) as db:
                names |= {name for (name,) in db.execute("SELECT name FROM topics")
                          if isinstance(name, str)}
    except SQLITE_FAILURES:
        return None
    return names


class Db3Bag:
    """The storage files of one bag, their topics and a type store for their messages."""

    def __init__(self, path: Path, storages: list[Path]) -> None:
        self.path, self.storages = path, storages
        self.topics: dict[str, str] = {}                 # topic → message type
        definitions: list[tuple[str, str, str]] = []
        try:
            for storage in storages:
                with closing(_connect(storage)) as db:
                    self.topics |= {name: msgtype for name, msgtype in db.execute(
                        "SELECT name, type FROM topics")
                        if isinstance(name, str) and isinstance(msgtype, str)}
                    tables = {row[0] for row in db.execute(
                        "SELECT name FROM sqlite_master WHERE type = 'table'")}
                    if "message_definitions" in tables:
                        definitions += db.execute(
                            "SELECT topic_type, encoding, encoded_message_definition "
                            "FROM message_definitions").fetchall()
        except SQLITE_FAILURES as error:
            raise LogError(path, f"cannot open db3 log: {_problem(error)}") from None
        self.store = _typestore(definitions, set(self.topics.values()))

    def span(self) -> tuple[int | None, int | None]:
        firsts, lasts = [], []
        for storage in self.storages:
            with closing(_connect(storage)) as db:
                first, last = db.execute(
                    "SELECT MIN(timestamp), MAX(timestamp) FROM messages").fetchone()
            if isinstance(first, int) and isinstance(last, int):   # else damaged cells
                firsts.append(first)
                lasts.append(last)
        return min(firsts, default=None), max(lasts, default=None)

    def read(self, collector: SignalCollector) -> Signals:
        collector.require_topics(self.topics)
        wanted = [t for t in self.topics if t in collector.topics]
        batches = TopicBatches(collector, self.topics, True, self.store,
                               self.store.deserialize_cdr)

        def feed() -> None:
            for storage in self.storages:
                with closing(_connect(storage)) as db:
                    ids = {topic_id: name for topic_id, name in db.execute(
                        "SELECT id, name FROM topics") if name in wanted}
                    marks = ",".join("?" * len(ids))
                    cursor = db.execute("SELECT topic_id, timestamp, data FROM messages "
                                        f"WHERE topic_id IN ({marks})", list(ids))
                    while rows := _fetch(cursor):
                        _hand_over(rows, ids, batches)

        batches.fill(feed)
        try:
            span = self.span()
        except SQLITE_FAILURES:      # the damage is already noted; the data gives the span
            span = (None, None)
        return collector.finish("db3", *span, self.topics)

    def inventory(self) -> LogInventory:
        counts: dict[str, int] = dict.fromkeys(self.topics, 0)
        try:
            for storage in self.storages:
                with closing(_connect(storage)) as db:
                    names = dict(db.execute("SELECT id, name FROM topics").fetchall())
                    for topic_id, count in db.execute(
                            "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id"):
                        if topic_id in names and names[topic_id] in counts:
                            counts[names[topic_id]] += int(count)
            span = self.span()
        except SQLITE_FAILURES as error:
            raise LogError(self.path, f"damaged db3 log: {_problem(error)}") from None
        topics = [TopicInfo(topic, self.topics[topic], count,
                            tuple(ros_field_paths(self.store, self.topics[topic])))
                  for topic, count in sorted(counts.items())]
        return LogInventory("db3", *span, topics)


def _fetch(cursor: sqlite3.Cursor) -> list[tuple[int, int, bytes]]:
    try:
        return cursor.fetchmany(ROWS_AT_ONCE)
    except MemoryError:
        raise sqlite3.DatabaseError("a record declares more bytes than sqlite will read "
                                    "(database disk image is malformed)") from None


def _hand_over(rows: list[tuple[int, int, bytes]], topics: dict[int, str],
               batches: TopicBatches) -> None:
    """One fetch of rows, split by topic, each topic's blobs joined into one buffer."""
    topic_ids, stamps, blobs = zip(*rows, strict=True)
    ids = np.fromiter(topic_ids, np.int64, len(rows))
    times_ns = np.fromiter(stamps, np.int64, len(rows))
    lengths = np.fromiter(map(len, blobs), np.int64, len(rows))
    for topic_id in np.unique(ids).tolist():
        chosen = np.flatnonzero(ids == topic_id)
        data = np.frombuffer(b"".join([blobs[i] for i in chosen.tolist()]), np.uint8)
        ends = np.cumsum(lengths[chosen])
        batches.extend(topics[topic_id], times_ns[chosen], data, ends - lengths[chosen], ends)


def _typestore(definitions: Iterable[tuple[str, str, str]], msgtypes: set[str]) -> Any:
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

    types: dict[str, Any] = {}
    for msgtype, encoding, text in definitions:
        try:
            if encoding == "ros2msg" and text:
                types.update(get_types_from_msg(text, msgtype))
            elif encoding == "ros2idl" and text:
                blocks = text.split(IDL_SEPARATOR)[1:] if text.startswith(
                    f"{IDL_SEPARATOR}IDL: ") else [f"\n{text}"]
                for block in blocks:
                    types.update(get_types_from_idl(block.split("\n", 1)[1]))
        except Exception:  # a definition rosbags cannot parse: Humble's may still do
            continue
    if msgtypes - types.keys():
        types = get_typestore(Stores.ROS2_HUMBLE).fielddefs | types
    store = get_typestore(Stores.EMPTY)
    store.register(types)
    return store
