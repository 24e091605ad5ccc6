"""Shared SQLite detail of the embedded stores (campaign results, health history)."""

from __future__ import annotations

import sqlite3
import time


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
