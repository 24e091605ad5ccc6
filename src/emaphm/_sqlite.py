"""Shared SQLite detail of the embedded stores (campaign results, health history)."""

from __future__ import annotations

import os
import sqlite3
import time
from pathlib import Path


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
