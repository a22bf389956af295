"""SQLite tables read from their pages (`adapters.sqlite_pages`) against sqlite's own
reading of the same files, and the db3 reader that uses them: the same rows, values and
blobs; whatever the page reader does not follow goes to sqlite, from where it stopped."""

import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from helpers import assert_same_signals

import adapters.rosbag2_pages
import adapters.sqlite_pages
from adapters import read_log
from adapters.sqlite_pages import NotPlain, SqliteFile

# Every integer width SQLite stores (0/1 constants, 1, 2, 3, 4, 6 and 8 bytes), signed.
INTEGERS = [0, 1, -1, 127, -128, 255, 2**15 - 1, -2**15, 2**23 - 1, -2**23, 2**31 - 1,
            -2**31, 2**47 - 1, -2**47, 2**47, 2**63 - 1, -2**63]


def make_table(path: Path, rows: int, overflowing: bool = True, page_size: int = 512
               ) -> dict[int, tuple[int, int, bytes]]:
    """A table of ``rows`` rows (on 512-byte pages, a tree three levels deep and more),
    blobs of 0 to 300 bytes and (``overflowing``) a few that run onto overflow pages, some
    rows deleted; what it holds, by row id."""
    rng = np.random.default_rng(7)
    with sqlite3.connect(path) as db:
        db.execute(f"PRAGMA page_size = {page_size}")
        db.execute("CREATE TABLE t (id INTEGER PRIMARY KEY, a INTEGER, b INTEGER, data BLOB)")
        for row in range(rows):
            size = 4 * page_size if overflowing and row % 97 == 5 else int(rng.integers(0, 300))
            db.execute("INSERT INTO t (a, b, data) VALUES (?, ?, ?)",
                       (INTEGERS[row % len(INTEGERS)], int(rng.integers(-2**40, 2**40)),
                        rng.bytes(size)))
        db.execute("DELETE FROM t WHERE id % 13 = 0")     # freed cells and pages
        db.execute("INSERT INTO t (id, a, b, data) VALUES (?, 1, 2, x'00')", (10**12,))
        held = {row_id: (a, b, data) for row_id, a, b, data in
                db.execute("SELECT id, a, b, data FROM t")}
    db.close()
    return held


def root_of(path: Path, table: str) -> int:
    with sqlite3.connect(path) as db:
        (root,) = db.execute("SELECT rootpage FROM sqlite_master WHERE name = ?",
                             (table,)).fetchone()
    db.close()
    return int(root)


@pytest.mark.parametrize("page_size", [512, 65536])     # the header writes 65536 as 1
def test_a_tables_rows_read_from_its_pages_are_sqlites(tmp_path, monkeypatch, page_size):
    path = tmp_path / "table.sqlite"
    held = make_table(path, 3000, page_size=page_size)
    monkeypatch.setattr(adapters.sqlite_pages, "BYTES_AT_ONCE", 7 * page_size)  # many reads
    pages, seen, overflowing = SqliteFile(path), [], 0
    for records in pages.records(root_of(path, "t"), 4):
        seen += records.rowids.tolist()
        a, b = records.integers(1), records.integers(2)
        for row, row_id in enumerate(records.rowids.tolist()):
            assert (a[row], b[row]) == held[row_id][:2]
            try:
                start, end = records.blobs(3, np.array([row]))
            except NotPlain:                    # on overflow pages: not followed here
                assert len(held[row_id][2]) > page_size
                overflowing += 1
                continue
            assert records.data[start[0]:end[0]].tobytes() == held[row_id][2]
    pages.close()
    assert seen == sorted(held) and overflowing >= 20


def test_what_the_page_reader_does_not_follow_is_refused(tmp_path):
    path = tmp_path / "table.sqlite"
    make_table(path, 200)
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE k (name TEXT PRIMARY KEY, value INTEGER) WITHOUT ROWID")
        db.execute("INSERT INTO k VALUES ('a', 1)")
        db.execute("CREATE TABLE s (id INTEGER PRIMARY KEY, name TEXT)")
        db.execute("INSERT INTO s (name) VALUES ('a')")
    db.close()
    pages = SqliteFile(path)
    with pytest.raises(NotPlain):              # an index tree, not a rowid table
        list(pages.records(root_of(path, "k"), 2))
    with pytest.raises(NotPlain):              # a table of four columns read as three
        next(pages.records(root_of(path, "t"), 3))
    with pytest.raises(NotPlain):              # a text value is not an integer
        next(pages.records(root_of(path, "s"), 2)).integers(1)
    pages.close()
    Path(f"{path}-wal").write_bytes(b"\0" * 32)
    with pytest.raises(NotPlain):              # changes not yet in the file
        SqliteFile(path)
    (tmp_path / "text").write_text("not a database\n" * 20)
    with pytest.raises(NotPlain):
        SqliteFile(tmp_path / "text")


def test_damaged_pages_are_refused_or_read_never_crash(tmp_path):
    """Overwritten bytes anywhere in the file: the reader reads on or refuses, and what
    it reads keeps its promises (rows in order, values inside their pages)."""
    path = tmp_path / "table.sqlite"
    make_table(path, 600, overflowing=False)
    data, root = path.read_bytes(), root_of(path, "t")
    rng = np.random.default_rng(3)
    refused = 0
    for trial in range(300):
        damaged = bytearray(data)
        at = int(rng.integers(0, len(data) - 8))
        damaged[at:at + 4] = rng.bytes(4)
        copy = tmp_path / f"damaged{trial}.sqlite"
        copy.write_bytes(damaged)
        try:
            pages = SqliteFile(copy)
            for records in pages.records(root, 4):
                assert (np.diff(records.rowids) > 0).all()
                records.integers(1)
                records.integers(2)
                starts, ends = records.blobs(3, np.arange(records.rowids.size))
                assert (starts >= 0).all() and (ends <= records.data.size).all()
            pages.close()
        except NotPlain:
            refused += 1
        copy.unlink()
    assert 0 < refused < 300


@pytest.fixture(scope="module")
def db3_dive(tmp_path_factory, dive_cache, profile) -> Path:
    from auvdiag_cli.simulator.writers import write_log

    path = tmp_path_factory.mktemp("pages") / "dive"
    write_log(dive_cache("paper-flow-sensor-covered", 31), profile, path, "db3")
    return path


def sqlite_only(monkeypatch) -> None:
    def refuse(*_: object) -> SqliteFile:
        raise NotPlain("refused for the comparison")
    monkeypatch.setattr(adapters.rosbag2_pages, "SqliteFile", refuse)


def test_a_db3_read_from_its_pages_equals_sqlites_read(db3_dive, profile, monkeypatch):
    used = []
    real = adapters.rosbag2_pages.read_pages

    def watched(*args: object) -> adapters.rosbag2_pages.PagesRead:
        used.append(real(*args))                            # type: ignore[arg-type]
        return used[-1]

    monkeypatch.setattr("adapters.rosbag2_sqlite.read_pages", watched)
    from_pages = read_log(db3_dive, profile.sources)
    assert used and all(progress.whole for progress in used)
    monkeypatch.undo()
    sqlite_only(monkeypatch)
    through_sqlite = read_log(db3_dive, profile.sources)
    assert not from_pages.notes and not through_sqlite.notes
    assert_same_signals(from_pages, through_sqlite)
    assert (from_pages.start_ns, from_pages.end_ns) == (through_sqlite.start_ns,
                                                        through_sqlite.end_ns)
    assert from_pages.messages_read == through_sqlite.messages_read


def test_where_the_pages_stop_sqlite_reads_on(db3_dive, tmp_path, profile, monkeypatch):
    """The page reader refuses a later batch of pages: the rows before it came from the
    pages, sqlite reads the rest, and no message is lost or read twice."""
    bag = tmp_path / "bag"
    shutil.copytree(db3_dive, bag)
    sqlite_only(monkeypatch)
    reference = read_log(bag, profile.sources)
    monkeypatch.undo()
    monkeypatch.setattr(adapters.sqlite_pages, "BYTES_AT_ONCE", 16 * 4096)
    real_blobs, real_read, calls, progress = adapters.sqlite_pages.Records.blobs, \
        adapters.rosbag2_pages.read_pages, [], []

    def refuse_later(self: adapters.sqlite_pages.Records, column: int, rows: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
        calls.append(column)
        if len(calls) > 10:
            raise NotPlain("a blob continues on overflow pages")
        return real_blobs(self, column, rows)

    def watched(*args: object) -> adapters.rosbag2_pages.PagesRead:
        progress.append(real_read(*args))                  # type: ignore[arg-type]
        return progress[-1]

    monkeypatch.setattr(adapters.sqlite_pages.Records, "blobs", refuse_later)
    monkeypatch.setattr("adapters.rosbag2_sqlite.read_pages", watched)
    read = read_log(bag, profile.sources)
    assert not progress[0].whole and progress[0].last_row > 0
    assert_same_signals(read, reference)
    assert read.messages_read == reference.messages_read
    assert (read.start_ns, read.end_ns) == (reference.start_ns, reference.end_ns)
