"""The results of an assessment's units as they finish: one SQLite file, one row per unit,
committed one by one (write-ahead log), so that a killed assessment resumes where it
stopped. The spec it holds must be the one resumed (its hash), or the store refuses.
A store that cannot be written (a full disk, a read-only folder) is an
:class:`~emaphm.assessment.spec.AssessmentError` that says so: what was committed stays,
and the same command resumes once there is room.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Any

from .._sqlite import enable_wal
from .spec import AssessmentError, AssessmentSpec

__all__ = ["AssessmentStore", "SCHEMA_VERSION"]

#: The layout of the store (``PRAGMA user_version``).
SCHEMA_VERSION = 1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS units (
    key TEXT PRIMARY KEY, phase TEXT NOT NULL, idx INTEGER NOT NULL, result TEXT NOT NULL);
"""


def _cannot_write(path: Path, exc: sqlite3.Error) -> AssessmentError:
    """The refusal of a store SQLite cannot write: its cause, and that the units committed
    are kept."""
    text = str(exc)
    cause = ("the disk is full" if "full" in text else
             "the disk or the file cannot be written" if "I/O" in text or "readonly" in text
             else text)
    return AssessmentError(f"{path}: cannot write the assessment's store: {cause} (SQLite: "
                           f"{text}); the units done are kept in {path.parent}: free some space "
                           "(or fix the folder's permissions) and run the same command again "
                           "to resume")


class AssessmentStore:
    """An assessment's unit results (:meth:`open`, :meth:`put`, :meth:`results`)."""

    def __init__(self, path: Path, conn: sqlite3.Connection) -> None:
        self.path = path
        self._conn = conn

    @classmethod
    def open(cls, path: str | Path, spec: AssessmentSpec) -> "AssessmentStore":
        """Open (or create) the store of ``spec`` at ``path``; an existing store of another
        spec is refused with the differences."""
        path = Path(path)
        try:
            return cls._open(path, spec)
        except sqlite3.OperationalError as exc:
            raise _cannot_write(path, exc) from None

    @classmethod
    def _open(cls, path: Path, spec: AssessmentSpec) -> "AssessmentStore":
        conn = sqlite3.connect(path, timeout=30.0, isolation_level=None)
        try:
            enable_wal(conn)
            version = conn.execute("PRAGMA user_version").fetchone()[0]
            if version not in (0, SCHEMA_VERSION):
                raise AssessmentError(f"{path} is an assessment store of layout {version}; this "
                                      f"emaphm writes layout {SCHEMA_VERSION}: remove it")
            conn.executescript(_SCHEMA)
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            row = conn.execute("SELECT value FROM meta WHERE key = 'spec'").fetchone()
            if row is None:
                conn.execute("INSERT INTO meta VALUES ('spec', ?)", (spec.to_json(),))
            else:
                stored = AssessmentSpec.from_dict(json.loads(row[0]))
                if stored.hash() != spec.hash():
                    diff = "; ".join(spec.differences(stored)[:4])
                    raise AssessmentError(
                        f"{path.parent} holds an unfinished assessment with other settings "
                        f"({diff}); rerun it with its settings to resume, or remove "
                        f"{path.parent} to start again")
        except BaseException:
            conn.close()
            raise
        return cls(path, conn)

    def put(self, result: dict[str, Any]) -> None:
        try:
            self._conn.execute("INSERT OR REPLACE INTO units VALUES (?, ?, ?, ?)",
                               (result["key"], result["phase"], int(result["index"]),
                                json.dumps(result, sort_keys=True)))
        except sqlite3.OperationalError as exc:
            raise _cannot_write(self.path, exc) from None

    def results(self, phase: str) -> dict[str, dict[str, Any]]:
        """The stored results of ``phase`` by key (failures included: they carry ``error``)."""
        rows = self._conn.execute("SELECT key, result FROM units WHERE phase = ? ORDER BY idx",
                                  (phase,)).fetchall()
        return {k: json.loads(r) for k, r in rows}

    def close(self, strict: bool = True) -> None:
        """Fold the log into the file and close. Where that cannot be written (a full disk),
        the log keeps every committed unit (the next open reads it): an AssessmentError
        with ``strict``, else (an error already on its way) nothing more is said."""
        try:
            self._conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        except sqlite3.OperationalError as exc:
            if strict:
                raise _cannot_write(self.path, exc) from None
        finally:
            self._conn.close()

    def __enter__(self) -> "AssessmentStore":
        return self

    def __exit__(self, kind: Any, *exc: Any) -> None:
        self.close(strict=kind is None)
