"""Shared SQLite detail of the embedded stores (campaign results, health history): the
names a store may have, a read-only open that changes nothing, why a store cannot be
written, write-ahead logging and the journal files a refused store must not keep."""

from __future__ import annotations

import os
import sqlite3
import time
import urllib.parse
from pathlib import Path

from ._files import folder_problem

#: The first 16 bytes of every SQLite 3 database file.
SQLITE_HEADER = b"SQLite format 3\x00"


def store_name_problem(path: str | os.PathLike[str]) -> str | None:
    """What is wrong with ``path`` as the name of a store file, or None: an empty name
    (SQLite makes a temporary database of it) and ``:memory:`` (SQLite's in-memory
    database) are gone when the command ends, and what was recorded with them too."""
    text = os.fspath(path)
    if not text.strip():
        return "is empty"
    if text == ":memory:":
        return ("names SQLite's in-memory database, which is gone, with everything recorded "
                "in it, when the command ends")
    return None


def write_problem(path: Path) -> str | None:
    """Why the existing database file ``path`` cannot be written, or None: the file itself
    (opened for writing and closed, which changes nothing) and its folder, where SQLite
    writes its journal files (tried as the operating system decides, root included)."""
    try:
        fd = os.open(path, os.O_RDWR | getattr(os, "O_BINARY", 0))
    except OSError as exc:
        return f"the file is read-only ({exc.strerror or exc})"
    os.close(fd)
    problem = folder_problem(path.parent)
    if problem is not None:
        return (f"its folder {path.parent} is not writable ({problem}), and SQLite writes its "
                "journal files beside the database")
    return None


def connect_readonly(path: Path, timeout: float) -> sqlite3.Connection:
    """A connection that only reads ``path`` (``mode=ro``): it works on a file and in a
    folder this process cannot write, and leaves the file as it is.

    A write-ahead-log database needs its ``-shm`` file; where the folder is read-only and
    there is none, the file is opened ``immutable`` (no locks, no shared memory), which
    is sound because nobody can be writing it there: a writer would need the same folder.
    A log that still holds changes is never skipped that way (SQLite's error is raised).
    """
    # the path's bytes, %-quoted: any name the OS holds (a Latin-1 name, or any non-ASCII
    # name under LC_ALL=C), not only those that encode as UTF-8
    uri = f"file:{urllib.parse.quote(os.fsencode(Path(path).resolve()))}?mode=ro"
    conn = sqlite3.connect(uri, uri=True, timeout=timeout, isolation_level=None)
    try:
        conn.execute("SELECT count(*) FROM sqlite_master").fetchone()
        return conn
    except sqlite3.OperationalError:
        conn.close()
        wal = Path(f"{path}-wal")
        if (wal.exists() and wal.stat().st_size > 0) or folder_problem(Path(path).parent) is None:
            raise
    return sqlite3.connect(uri + "&immutable=1", uri=True, timeout=timeout, isolation_level=None)


def enable_wal(conn: sqlite3.Connection, seconds: float = 60.0) -> str:
    """Switch ``conn``'s database to write-ahead logging; return the journal mode.

    Changing the journal mode needs an exclusive lock, and SQLite answers
    "database is locked" at once, without its busy handler, while another
    process holds a lock (two processes opening a new store together): retry
    for up to ``seconds``.
    """
    deadline = time.monotonic() + seconds
    while True:
        try:
            return str(conn.execute("PRAGMA journal_mode = WAL").fetchone()[0])
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) or time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def journal_files(path: str | os.PathLike[str]) -> list[Path]:
    """The write-ahead log and shared-memory files of the database at ``path`` that do not
    exist yet: opening a WAL database creates them, and a refused (damaged, foreign) store
    must be left as it was found (see :func:`remove_journal_files`)."""
    p = Path(path)
    return [q for q in (Path(f"{p}-wal"), Path(f"{p}-shm")) if not q.exists()]


def remove_journal_files(created: list[Path]) -> None:
    """Remove the journal files in ``created`` (from :func:`journal_files`, before the
    open) after the connection is closed, if the log holds nothing: what was only read
    leaves no file behind."""
    wal = [q for q in created if q.name.endswith("-wal")]
    if any(q.exists() and q.stat().st_size > 0 for q in wal):
        return
    for q in created:
        try:
            q.unlink()
        except FileNotFoundError:
            pass
