"""A db3 storage file's messages read from its pages (`adapters.sqlite_pages`): the wanted
topics' blobs handed over where they lie in the pages, a few thousand pages at a time.
Where the file holds anything that reader does not follow, reading stops at the last row
handed over and the caller goes on through sqlite from there."""

import sqlite3
from collections.abc import Callable
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adapters.sqlite_pages import NotPlain, SqliteFile

Span = tuple[int | None, int | None]
# topic name, times (ns), the pages' bytes, where each message begins and ends there
HandOver = Callable[[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]


@dataclass(frozen=True)
class MessagesTable:
    """Where rosbag2's messages table lies in a file, and which column holds what."""

    root: int
    columns: int
    topic_id: int
    timestamp: int
    data: int

    @classmethod
    def of(cls, db: sqlite3.Connection) -> "MessagesTable | None":
        """The table's layout, or None where its key is not the row id, a column is
        missing or the schema cannot be read (sqlite then reads it, and names any damage)."""
        try:
            found = db.execute("SELECT rootpage FROM sqlite_master "
                               "WHERE type = 'table' AND name = 'messages'").fetchone()
            columns = db.execute("PRAGMA table_info(messages)").fetchall()
        except sqlite3.Error:
            return None
        names = [str(name) for _, name, *_ in columns]
        keys = [(name, str(kind).upper()) for _, name, kind, _, _, key in columns if key]
        if (found is None or not isinstance(found[0], int) or keys != [("id", "INTEGER")]
                or not {"topic_id", "timestamp", "data"} <= set(names)):
            return None
        return cls(found[0], len(names), names.index("topic_id"), names.index("timestamp"),
                   names.index("data"))


@dataclass
class PagesRead:
    """How far a storage file was read from its pages."""

    last_row: int = 0           # rows after this id are still to read
    first_ns: int | None = None
    last_ns: int | None = None
    whole: bool = False         # every row was read: the span is the file's

    def span(self) -> Span:
        return (self.first_ns, self.last_ns) if self.whole else (None, None)

    def saw(self, stamps: np.ndarray) -> None:
        if stamps.size:
            low, high = int(stamps.min()), int(stamps.max())
            self.first_ns = low if self.first_ns is None else min(self.first_ns, low)
            self.last_ns = high if self.last_ns is None else max(self.last_ns, high)


def read_pages(storage: Path, db: sqlite3.Connection, topics: dict[int, str],
               hand_over: HandOver) -> PagesRead:
    """Hand over the wanted topics' messages of ``storage`` in row order from its pages,
    for as long as the file is one the page reader follows."""
    progress = PagesRead()
    table = MessagesTable.of(db)
    if table is None:
        return progress
    try:
        pages = SqliteFile(storage)
    except (NotPlain, OSError):
        return progress
    with closing(pages):
        try:
            for records in pages.records(table.root, table.columns):
                topic_ids = records.integers(table.topic_id)
                stamps = records.integers(table.timestamp)
                found = {name: rows for topic_id, name in topics.items()
                         if (rows := np.flatnonzero(topic_ids == topic_id)).size}
                placed = {name: records.blobs(table.data, rows) for name, rows in found.items()}
                for name, (starts, ends) in placed.items():   # all checked: now hand over
                    hand_over(name, stamps[found[name]], records.data, starts, ends)
                progress.saw(stamps)
                if records.rowids.size:
                    progress.last_row = int(records.rowids[-1])
        except NotPlain:
            return progress
    progress.whole = True
    return progress
