"""ROS 2 bags in sqlite3 storage (``.db3``, one file or a bag split over several), their
messages' fields read column-wise instead of one Python object per message. Each storage
file's messages table is read from the file's pages (`adapters.rosbag2_pages`); from
wherever those hold what that reader does not follow, one SQL query for the wanted topics
reads on, the blobs handed over a fetch at a time.

Message definitions come from the bag's ``message_definitions`` table (Iron and later);
types it does not define (Humble and older write none) come from ROS 2 Humble's."""

import sqlite3
from collections.abc import Generator, Iterable, Iterator
from contextlib import closing, suppress
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from adapters.collect import SignalCollector
from adapters.fieldnames import ros_field_paths
from adapters.inventory import LogInventory, TopicInfo
from adapters.limits import MAX_CHUNK_BYTES
from adapters.ros_columns import TopicBatches
from adapters.rosbag2 import Rosbag2Adapter
from adapters.rosbag2_pages import Span, read_pages
from adapters.signals import LogSources, Signals
from auvdiag_errors import LogError

ROWS_AT_ONCE = 20_000          # rows fetched per round trip: bounds memory on long bags
CREPT_AT_ONCE = 1000           # rows read one at a time (up to damage) handed over together
# sqlite reports a damaged record that declares more bytes than it will allocate as "out of
# memory", which Python raises as MemoryError; an error message quoting a damaged schema
# is not UTF-8, which Python raises as UnicodeDecodeError. From a query, both are damage.
SQLITE_FAILURES = (sqlite3.Error, MemoryError, UnicodeDecodeError)
IDL_SEPARATOR = "=" * 80 + "\n"
# Past damaged pages: strides of 1, 2, 4 … row ids, up to 2**40 rows ahead.
STRIDES_AT_MOST = 40
MAX_ROW_ID = 2**63 - 1
Row = tuple[int, int, bytes]               # topic_id, timestamp, data


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


class Db3Adapter(Rosbag2Adapter):
    """A ROS 2 bag in sqlite3 storage."""

    def read_storages(self, storages: list[Path], path: Path, sources: LogSources, fmt: str
                      ) -> Signals:
        return Db3Bag(path, storages).read(SignalCollector(path, sources))

    def storages_inventory(self, storages: list[Path], path: Path, fmt: str) -> LogInventory:
        return Db3Bag(path, storages).inventory()


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

    def span(self) -> Span:
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

        spans: list[Span] = []

        def feed() -> None:
            for storage in self.storages:
                with closing(_connect(storage)) as db:
                    ids = {topic_id: name for topic_id, name in db.execute(
                        "SELECT id, name FROM topics") if name in wanted}
                    paged = read_pages(storage, db, ids, batches.hand_over_in_place)
                    spans.append(paged.span())
                    if paged.whole:
                        continue
                    rows = _WantedRows(db, list(ids), collector, storage)
                    rows.next_id = paged.last_row + 1
                    for fetched in rows:
                        _hand_over(fetched, ids, batches)

        batches.fill(feed)
        return collector.finish("db3", *self._span(spans), self.topics)

    def _span(self, spans: list[Span]) -> Span:
        """The bag's first and last message time: from the pages where every file was read
        from them, else from sqlite (None where damage hides it: the data then tells)."""
        if len(spans) == len(self.storages) and all(first is not None for first, _ in spans):
            return (min(first for first, _ in spans if first is not None),
                    max(last for _, last in spans if last is not None))
        try:
            return self.span()
        except SQLITE_FAILURES:
            return (None, None)

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


class _WantedRows:
    """The wanted topics' messages of one storage file in storage order, a fetch at a time
    (topic, time and data only: a row id with each would cost a tenth of the read). Past
    damaged pages the reading goes on at the next row sqlite can read, noted as damage: the
    last readable row before them is found one row at a time, then the fewest row ids
    ahead from which sqlite reads again (strides that double until one reads, then halve
    back); the damage is raised when no stride gets past it."""

    def __init__(self, db: sqlite3.Connection, topic_ids: list[int],
                 collector: SignalCollector, storage: Path) -> None:
        self.db, self.topic_ids, self.collector, self.storage = db, topic_ids, collector, storage
        marks = ",".join("?" * len(topic_ids))
        # ``id >=``, not ``id >``: sqlite seeks ``id > N`` through the page holding N, so
        # past a damaged page only the first id after it can be asked for.
        self.where = f"FROM messages WHERE topic_id IN ({marks}) AND id >= ? ORDER BY id"
        self.next_id = 1         # rows from this id on are still to read (rosbag2 counts from 1)

    def __iter__(self) -> Iterator[list[Row]]:
        while not (yield from self._bulk()):
            try:
                yield from self._creep()
                return
            except SQLITE_FAILURES as damage:
                self._step_over(damage)

    def _bulk(self) -> Generator[list[Row], None, bool]:
        """Fetches from ``next_id`` on; whether they reached the end (else ``next_id`` is
        past every row handed over, and damage stopped them)."""
        begin, fetched = self.next_id, 0
        try:
            cursor = self.db.execute(f"SELECT topic_id, timestamp, data {self.where}",
                                     [*self.topic_ids, begin])
            while rows := _fetch(cursor, ROWS_AT_ONCE):
                fetched += len(rows)
                yield rows
        except SQLITE_FAILURES:
            if fetched:
                self.next_id = max(self.next_id, self._id_after(begin, fetched - 1) + 1)
            return False
        return True

    def _creep(self) -> Iterator[list[Row]]:
        """One row at a time, each with its id, up to the damage; handed over in batches.
        Python's sqlite3 steps to the next row before it returns one, so the last row
        before damaged pages comes back as the error; asked for alone (``LIMIT 1`` stops
        before the next row) it reads."""
        query = f"SELECT id, topic_id, timestamp, data {self.where}"
        cursor = self.db.execute(query, [*self.topic_ids, self.next_id])
        crept: list[Row] = []
        damage: BaseException | None = None
        try:
            while fetched := _fetch(cursor, 1):
                crept.append(self._handed(fetched[0]))
                if len(crept) == CREPT_AT_ONCE:
                    yield crept
                    crept = []
        except SQLITE_FAILURES as error:
            damage = error
            with suppress(*SQLITE_FAILURES):
                if fetched := _fetch(self.db.execute(f"{query} LIMIT 1",
                                                     [*self.topic_ids, self.next_id]), 1):
                    crept.append(self._handed(fetched[0]))
        if crept:
            yield crept
        if damage is not None:
            raise damage

    def _handed(self, row: tuple[int, int, int, bytes]) -> Row:
        row_id, topic_id, stamp, data = row
        self.next_id = max(self.next_id, row_id + 1)     # damaged pages can misorder ids
        return topic_id, stamp, data

    def _step_over(self, damage: BaseException) -> None:
        """Move ``next_id`` past the damaged pages at it, noting the rows lost."""
        failed, stride = 0, 1
        readable, found = self._probe(self.next_id + stride)
        while not readable:
            failed, stride = stride, 2 * stride
            if stride > 2**STRIDES_AT_MOST or self.next_id + stride >= MAX_ROW_ID:
                raise damage
            readable, found = self._probe(self.next_id + stride)
        while stride - failed > 1:
            middle = (failed + stride) // 2
            readable, first = self._probe(self.next_id + middle)
            if readable:
                stride, found = middle, first
            else:
                failed = middle
        lost = f"rows {self.next_id} to {found - 1}" if found is not None else \
            f"the rows from {self.next_id} on"
        _stepped_over(self.collector, f"{self.storage.name}: {lost} unreadable (damaged "
                      "pages); read on after them")
        self.next_id = found if found is not None else self.next_id + stride

    def _probe(self, begin: int) -> tuple[bool, int | None]:
        """Whether sqlite reads the rows from id ``begin`` on, and the first wanted one's id
        (``begin`` at least: a damaged tree can answer with a smaller one)."""
        try:
            found = self.db.execute(f"SELECT id {self.where} LIMIT 1",
                                    [*self.topic_ids, begin]).fetchone()
        except SQLITE_FAILURES:
            return False, None
        return True, None if found is None else max(int(found[0]), begin)

    def _id_after(self, begin: int, skip: int) -> int:
        """The id of the wanted row ``skip`` rows past the first from ``begin`` on."""
        (found,) = self.db.execute(f"SELECT id {self.where} LIMIT 1 OFFSET ?",
                                   [*self.topic_ids, begin, skip]).fetchone()
        return int(found)


def _stepped_over(collector: SignalCollector, what: str) -> None:
    """The first damage stepped over is the log's; any further one is a note."""
    if collector.damage is None:
        collector.damaged(what)
    else:
        collector.notes.append(what)


def _fetch(cursor: sqlite3.Cursor, size: int) -> list[Any]:
    try:
        return cursor.fetchmany(size)
    except MemoryError:
        raise sqlite3.DatabaseError("a record declares more bytes than sqlite will read "
                                    "(database disk image is malformed)") from None


def _hand_over(rows: list[Row], topics: dict[int, str], batches: TopicBatches) -> None:
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
