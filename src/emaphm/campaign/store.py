"""The result store of a campaign: one SQLite file (embedded, no service to run).

Layout (schema version :data:`SCHEMA_VERSION`, in ``PRAGMA user_version`` as the health
history keeps its own)::

    meta(key PRIMARY KEY, value)   emaphm_version (of the creator), spec_json, spec_hash,
                                   name, created_at
    runs(run_key UNIQUE, ...)      one row per finished run (see RunResult)

Version 2 kept its number in ``meta.schema_version`` (``user_version`` 0) with the same
tables: a writing open moves it to ``user_version`` (one transaction); a read-only open
reads such a store as it is.

Guarantees
----------
* **Atomic, durable runs.** Each finished run is committed in its own transaction
  (``BEGIN IMMEDIATE`` ... ``COMMIT``, WAL journal, ``synchronous=FULL``): a process
  killed at any instant, SIGKILL included, leaves every run either fully stored or
  absent, never half-written.
* **Exactly once.** ``run_key`` is UNIQUE. A successful run is never overwritten; a
  failure row is replaced when a later attempt succeeds (reruns retry failures).
* **Several writers.** Two processes may write the same store: SQLite serialises
  their transactions (a writer waits up to a minute for the lock), and the UNIQUE key
  with ``ON CONFLICT`` keeps the first successful result of a run.
* **Nothing destroyed on bad input.** Opening checks, *before writing anything*, that
  the file is an emaphm store of a schema this version reads and that the given spec
  is the stored one; otherwise it raises a :class:`StoreError` that says what differs
  and how to proceed, and the file is left as it was.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import socket
import sqlite3
from contextlib import contextmanager
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any, Iterator, Mapping

from emaphm import __version__
from emaphm._files import folder_problem, regular_file
from emaphm._sqlite import (SQLITE_HEADER, connect_readonly, enable_wal, journal_files,
                            remove_journal_files, store_name_problem, write_problem)

from .spec import CampaignSpec, Run, SpecError

__all__ = [
    "SCHEMA_VERSION",
    "CampaignStore",
    "IncompatibleStoreError",
    "RunResult",
    "SpecMismatchError",
    "StoreError",
]

#: Version of the store, in ``PRAGMA user_version``; a store of another version is refused,
#: untouched. Version 2 (the same tables) kept it in ``meta.schema_version``.
SCHEMA_VERSION = 3

#: The version kept in the meta table before it moved to ``user_version``.
_META_VERSION = 2

_SQLITE_HEADER = SQLITE_HEADER

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS runs (
    run_key            TEXT NOT NULL UNIQUE,
    run_index          INTEGER NOT NULL,
    scenario           TEXT NOT NULL,
    algorithm          TEXT NOT NULL,
    optimizer          TEXT NOT NULL,
    run                INTEGER NOT NULL,
    seed               INTEGER NOT NULL,
    noise_seed         INTEGER NOT NULL,
    spawn_key          TEXT NOT NULL,
    status             TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
    error_text         TEXT,
    k_true             TEXT NOT NULL,
    k                  TEXT,
    fitness            REAL,
    error_pct          REAL,
    k_raw              TEXT,
    fitness_raw        REAL,
    error_pct_raw      REAL,
    evaluations        INTEGER,
    iterations         INTEGER,
    polish_evaluations INTEGER,
    run_evaluations    INTEGER,
    restarts           INTEGER,
    suspect            INTEGER,
    elapsed_s          REAL,
    kernel_s           REAL,
    simulate_s         REAL,
    reason             TEXT,
    diverged           INTEGER,
    history            TEXT,
    version            TEXT NOT NULL,
    worker             TEXT,
    finished_at        TEXT NOT NULL
);
"""


class StoreError(ValueError):
    """A store cannot be used as asked; the message says why and what to do."""


class IncompatibleStoreError(StoreError):
    """The file is not an emaphm store, or one of another schema or software version."""


class SpecMismatchError(StoreError):
    """The spec given is not the spec the store was created with."""

    def __init__(self, message: str, differences: list[str]) -> None:
        super().__init__(message)
        self.differences = differences


# ----------------------------------------------------------------------------- results


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


@dataclass(frozen=True)
class RunResult:
    """The outcome of one run, as stored (one row of ``runs``).

    ``status`` is ``"ok"`` or ``"failed"`` (then ``error_text`` holds the exception and
    the numeric fields are None). ``elapsed_s`` is the identification's wall time
    (metaheuristic plus polish, the paper's "time"); ``simulate_s`` the reference-model
    simulation of the measured trace; ``history`` the best fitness after each iteration,
    then after each polish poll. ``k``/``fitness``/``error_pct`` are after the polish,
    the ``*_raw`` ones the metaheuristic's own (equal without polish).
    """

    key: str
    index: int
    scenario: str
    algorithm: str
    optimizer: str
    run: int
    seed: int
    noise_seed: int
    spawn_key: tuple[int, ...]
    status: str
    k_true: tuple[float, ...]
    error_text: str | None = None
    k: tuple[float, ...] | None = None
    fitness: float | None = None
    error_pct: float | None = None
    k_raw: tuple[float, ...] | None = None
    fitness_raw: float | None = None
    error_pct_raw: float | None = None
    evaluations: int | None = None
    iterations: int | None = None
    polish_evaluations: int | None = None
    run_evaluations: int | None = None
    restarts: int | None = None
    suspect: bool | None = None
    elapsed_s: float | None = None
    kernel_s: float | None = None
    simulate_s: float | None = None
    reason: str | None = None
    diverged: int | None = None
    history: tuple[float, ...] | None = None
    version: str = __version__
    worker: str | None = None
    finished_at: str | None = None

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @classmethod
    def from_identification(cls, run: Run, ident: Any, simulate_s: float) -> "RunResult":
        """Build from an :class:`emaphm.identify.Identification` of ``run``."""
        return cls(
            **_run_fields(run), status="ok",
            k=tuple(float(x) for x in ident.k), fitness=float(ident.fitness),
            error_pct=None if ident.error_pct is None else float(ident.error_pct),
            k_raw=None if ident.k_raw is None else tuple(float(x) for x in ident.k_raw),
            fitness_raw=None if ident.fitness_raw is None else float(ident.fitness_raw),
            error_pct_raw=None if ident.error_pct_raw is None else float(ident.error_pct_raw),
            evaluations=int(ident.evaluations), iterations=int(ident.iterations),
            polish_evaluations=int(ident.polish_evaluations),
            run_evaluations=int(ident.run_evaluations), restarts=int(ident.restarts),
            suspect=bool(ident.suspect), elapsed_s=float(ident.elapsed_s),
            kernel_s=float(ident.kernel_s), simulate_s=float(simulate_s), reason=str(ident.reason),
            diverged=int(ident.diverged), history=tuple(float(x) for x in ident.history),
            worker=f"{socket.gethostname()}:{os.getpid()}", finished_at=_now())

    @classmethod
    def failure(cls, run: Run, error_text: str) -> "RunResult":
        """A failed run: the error text and no numbers."""
        return cls(**_run_fields(run), status="failed", error_text=error_text,
                   worker=f"{socket.gethostname()}:{os.getpid()}", finished_at=_now())

    def to_dict(self) -> dict[str, Any]:
        """Every field, JSON-ready (the tuples as lists); :meth:`from_dict` reads it back."""
        return {name: list(v) if isinstance(v, tuple) else v for name, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "RunResult":
        """The run :meth:`to_dict` wrote."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"not a stored run: unknown field(s) {', '.join(unknown)}")
        kw = dict(data)
        for name in _JSON_FIELDS:
            if kw.get(name) is not None:
                kw[name] = tuple(int(x) if name == "spawn_key" else x for x in kw[name])
        return cls(**kw)

    def outcome(self) -> dict[str, Any]:
        """The reproducible part: what the same run gives again, bit for bit, on any
        executor (everything but timings, worker and date)."""
        d = asdict(self)
        for name in ("elapsed_s", "kernel_s", "simulate_s", "worker", "finished_at", "version"):
            d.pop(name)
        return d


def _run_fields(run: Run) -> dict[str, Any]:
    return {"key": run.key, "index": run.index, "scenario": run.scenario,
            "algorithm": run.algorithm, "optimizer": run.optimizer, "run": run.run,
            "seed": run.seed, "noise_seed": run.noise_seed, "spawn_key": tuple(run.spawn_key),
            "k_true": tuple(run.k_true)}


_COLUMNS = ("run_key", "run_index", "scenario", "algorithm", "optimizer", "run", "seed",
            "noise_seed", "spawn_key", "status", "error_text", "k_true", "k", "fitness",
            "error_pct", "k_raw", "fitness_raw", "error_pct_raw", "evaluations", "iterations",
            "polish_evaluations", "run_evaluations", "restarts", "suspect", "elapsed_s",
            "kernel_s", "simulate_s", "reason", "diverged",
            "history", "version", "worker", "finished_at")
_JSON_FIELDS = {"spawn_key", "k_true", "k", "k_raw", "history"}
_FIELD_OF = {"run_key": "key", "run_index": "index"}


def _to_json(value: Any) -> Any:
    # Python's JSON writes floats by repr (exact round trip) and inf as Infinity
    return None if value is None else json.dumps(list(value))


def _from_json(text: str | None) -> Any:
    return None if text is None else tuple(json.loads(text))


def _to_row(r: RunResult) -> tuple:
    row = []
    for col in _COLUMNS:
        name = _FIELD_OF.get(col, col)
        v = getattr(r, name)
        row.append(_to_json(v) if name in _JSON_FIELDS else v)
    return tuple(row)


def _from_row(row: sqlite3.Row) -> RunResult:
    kw = {}
    for col in _COLUMNS:
        name = _FIELD_OF.get(col, col)
        v = row[col]
        if name in _JSON_FIELDS:
            v = _from_json(v)
            if name == "spawn_key" and v is not None:
                v = tuple(int(x) for x in v)
        kw[name] = v
    return RunResult(**kw)


# ----------------------------------------------------------------------------- store


class CampaignStore:
    """An open campaign store. Open it with :meth:`open`; use it as a context manager.

    >>> store = CampaignStore.open("results.sqlite", spec)   # doctest: +SKIP
    """

    def __init__(self, path: Path, conn: sqlite3.Connection, meta: dict[str, str],
                 readonly: bool, created: list[Path] | None = None,
                 schema_version: int = SCHEMA_VERSION) -> None:
        self.path = path
        self._conn = conn
        self.meta = meta
        self.readonly = readonly
        self.schema_version = schema_version
        self.spec = CampaignSpec.from_json(meta["spec_json"])
        self._created = list(created or [])

    # ------------------------------------------------------------------ opening
    @classmethod
    def open(cls, path: str | os.PathLike[str], spec: CampaignSpec | None = None, *,
             readonly: bool = False) -> "CampaignStore":
        """Open the store at ``path``, creating it with ``spec`` if it does not exist.

        An existing store is checked before anything is written: it must be an emaphm
        store of schema :data:`SCHEMA_VERSION`, and ``spec`` (if given) must equal the
        stored spec. ``spec=None`` opens an existing store with its own spec (resume,
        report). ``readonly`` never writes (reports).
        """
        problem = store_name_problem(path)
        if problem is not None:
            raise StoreError(f"--store {os.fspath(path)!r} {problem}; give the path of a store "
                             "file, e.g. --store results.sqlite")
        p = Path(path)
        if p.is_dir():
            raise StoreError(f"{p} is a folder; give the path of a store file, e.g. {p / 'results.sqlite'}")
        if os.path.lexists(p):                  # a FIFO, a device or a link loop is no store
            regular_file(p, "campaign store", give="the path of a store file", error=StoreError)
        exists = p.exists() and p.stat().st_size > 0
        if exists and not readonly:
            why = write_problem(p)
            if why is not None:
                raise StoreError(f"cannot write the campaign store {p}: {why}; it was not "
                                 "changed. Make it writable (e.g. chmod u+w) or copy it; `emaphm "
                                 "report` reads it as it is")
        if exists:
            with open(p, "rb") as fh:
                header = fh.read(len(_SQLITE_HEADER))
            if header != _SQLITE_HEADER:
                raise IncompatibleStoreError(
                    f"{p} is not an emaphm campaign store (not a SQLite database); it was not "
                    f"changed. {_STORE_FIX}")
        elif readonly or spec is None:
            raise FileNotFoundError(f"no campaign store at {p}; run `emaphm campaign --store {p}` "
                                    "to create one")
        elif not p.parent.exists():
            raise FileNotFoundError(f"cannot create {p}: folder {p.parent} does not exist; create it first")
        elif (problem := folder_problem(p.parent)) is not None:
            raise StoreError(f"cannot create the campaign store {p}: cannot write in the folder "
                             f"{p.parent} ({problem}); give a --store in a folder you can write to")

        created = journal_files(p) if exists else []
        try:
            conn = _connect(p, readonly=readonly and exists)
        except sqlite3.DatabaseError as exc:
            remove_journal_files(created)
            raise IncompatibleStoreError(_damaged(p, str(exc))) from None
        try:
            if exists:
                _check_integrity(conn, p)
            meta = _read_meta(conn, p)
            if meta is None:                        # a new (or empty) file: create the store
                if readonly or spec is None:
                    raise IncompatibleStoreError(f"{p} is an empty SQLite database, not a campaign store")
                _create(conn, spec)
                meta = _read_meta(conn, p)
                assert meta is not None
            version = _check_schema(conn, meta, p)
            if version == _META_VERSION and not readonly:
                _migrate_meta_version(conn)
                version, meta = SCHEMA_VERSION, _read_meta(conn, p) or meta
            try:
                stored = CampaignSpec.from_json(meta["spec_json"])
            except SpecError as exc:
                raise IncompatibleStoreError(
                    f"{p}: its stored spec is not valid for this emaphm ({__version__}): {exc}. "
                    f"It was written by emaphm {meta.get('emaphm_version', '?')}; use that version "
                    "to resume or report it.") from None
            if spec is not None and spec.hash != stored.hash:
                diffs = stored.differences(spec)
                raise SpecMismatchError(
                    f"{p} holds a different campaign ({meta.get('name', '?')!r}); the store was not "
                    "changed. Differences (stored -> given):\n  - " + "\n  - ".join(diffs) +
                    f"\nTo continue the stored campaign, run `emaphm campaign --store {p}` without "
                    "spec options (it resumes its own spec); to run the new spec, give another "
                    "--store path.", diffs)
        except BaseException:
            conn.close()
            remove_journal_files(created)       # a refused store is left as it was found
            raise
        return cls(p, conn, meta, readonly=readonly, created=created if readonly else None,
                   schema_version=version)

    def close(self) -> None:
        self._conn.close()
        remove_journal_files(self._created)     # a read-only open leaves nothing behind
        self._created = []

    def __enter__(self) -> "CampaignStore":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # ------------------------------------------------------------------ properties
    @property
    def created_by(self) -> str:
        """emaphm version that created the store."""
        return self.meta.get("emaphm_version", "?")

    def versions(self) -> set[str]:
        """emaphm versions of the creator and of every stored row."""
        rows = self._conn.execute("SELECT DISTINCT version FROM runs").fetchall()
        return {self.created_by} | {r[0] for r in rows}

    def check_version(self, allow_mix: bool = False) -> None:
        """Refuse to add runs of this emaphm to a store of another version."""
        other = sorted(v for v in self.versions() if v != __version__)
        if other and not allow_mix:
            raise IncompatibleStoreError(
                f"{self.path} holds results of emaphm {', '.join(other)}; this is emaphm "
                f"{__version__}, whose runs may differ, so finishing the campaign would mix two "
                "versions. Resume it with the version that started it, start a new --store, or "
                "pass --allow-version-mix to mix them knowingly. The store was not changed.")

    # ------------------------------------------------------------------ writing
    @contextmanager
    def _transaction(self) -> Iterator[sqlite3.Connection]:
        if self.readonly:
            raise StoreError(f"{self.path} was opened read-only")
        self._conn.execute("BEGIN IMMEDIATE")
        try:
            yield self._conn
        except BaseException:
            self._conn.execute("ROLLBACK")
            raise
        self._conn.execute("COMMIT")

    def commit(self, result: RunResult) -> bool:
        """Store one finished run in its own transaction.

        Returns True if the row was written, False if the run was already stored as a
        success (a success is never overwritten; a failure is replaced).
        """
        if result.finished_at is None:
            result = replace(result, finished_at=_now())
        cols = ", ".join(_COLUMNS)
        marks = ", ".join("?" for _ in _COLUMNS)
        update = ", ".join(f"{c} = excluded.{c}" for c in _COLUMNS if c != "run_key")
        sql = (f"INSERT INTO runs ({cols}) VALUES ({marks}) ON CONFLICT(run_key) DO UPDATE SET "
               f"{update} WHERE runs.status != 'ok'")
        with self._transaction() as conn:
            cur = conn.execute(sql, _to_row(result))
        return cur.rowcount > 0

    # ------------------------------------------------------------------ reading
    def keys(self, status: str | None = "ok") -> set[str]:
        """Keys of the stored runs with ``status`` (None: all)."""
        if status is None:
            rows = self._conn.execute("SELECT run_key FROM runs").fetchall()
        else:
            rows = self._conn.execute("SELECT run_key FROM runs WHERE status = ?", (status,)).fetchall()
        return {r[0] for r in rows}

    def results(self, status: str | None = "ok") -> list[RunResult]:
        """Stored runs with ``status`` (None: all), in the spec's run order."""
        q = "SELECT * FROM runs" + ("" if status is None else " WHERE status = ?") + " ORDER BY run_index"
        rows = self._conn.execute(q, () if status is None else (status,)).fetchall()
        return [_from_row(r) for r in rows]

    def frame(self, status: str | None = "ok"):
        """The stored runs (``status`` ``"ok"``, ``"failed"`` or None for all) as a pandas
        DataFrame, one row per run indexed by its key: every field of :class:`RunResult`,
        the vectors ``k``, ``k_raw`` and ``k_true`` spread into ``k_<name>``... columns
        (:data:`emaphm.faults.K_NAMES`), ``history`` kept as a tuple. Needs pandas."""
        from ..faults import K_NAMES
        from ..frames import require_pandas, vector_columns

        pd = require_pandas("CampaignStore.frame()")
        rows = []
        for r in self.results(status):
            row = asdict(r)
            for name in ("k", "k_raw", "k_true"):
                vector_columns(row, name, row.pop(name), K_NAMES)
            row["spawn_key"] = tuple(row["spawn_key"])
            rows.append(row)
        df = pd.DataFrame(rows)
        return df.set_index("key") if rows else df

    def result(self, key: str) -> RunResult | None:
        row = self._conn.execute("SELECT * FROM runs WHERE run_key = ?", (key,)).fetchone()
        return None if row is None else _from_row(row)

    def counts(self) -> dict[str, int]:
        """``{"ok": n, "failed": m, "total": spec runs}``."""
        out = {"ok": 0, "failed": 0}
        for status, n in self._conn.execute("SELECT status, COUNT(*) FROM runs GROUP BY status"):
            out[status] = n
        out["total"] = self.spec.n_runs
        return out

    def integrity_check(self) -> str:
        """SQLite's own check: ``"ok"`` for a sound file."""
        return self._conn.execute("PRAGMA integrity_check").fetchone()[0]


# ----------------------------------------------------------------------------- helpers


def _connect(p: Path, readonly: bool) -> sqlite3.Connection:
    if readonly:                       # mode=ro, immutable where the folder is read-only
        conn = connect_readonly(p, 60.0)
    else:
        conn = sqlite3.connect(str(p), timeout=60.0, isolation_level=None)
    conn.row_factory = sqlite3.Row
    conn.execute("PRAGMA busy_timeout = 60000")
    if not readonly:
        conn.execute("PRAGMA synchronous = FULL")
    return conn


def _check_integrity(conn: sqlite3.Connection, p: Path) -> None:
    """SQLite's ``quick_check`` of an existing store: a damaged file is refused, unchanged,
    before any run is listed from it."""
    try:
        result = str(conn.execute("PRAGMA quick_check").fetchone()[0])
    except sqlite3.DatabaseError as exc:
        result = str(exc)
    if result != "ok":
        raise IncompatibleStoreError(_damaged(p, f"SQLite quick_check: {result[:200]}"))


def _damaged(p: Path, what: str) -> str:
    return (f"{p} is damaged ({what}); it was not changed and no run is read from it. Restore "
            "it from a backup, or start a new store with another --store path and run the "
            "campaign again (every run is reproducible from its seeds).")


#: The fix a file that is no campaign store is given: `emaphm campaign` takes it as --store,
#: `emaphm report` as its argument.
_STORE_FIX = ("Give the path of a store that emaphm campaign wrote (its --store), or, to "
              "start a campaign, a new path.")


def _read_meta(conn: sqlite3.Connection, p: Path) -> dict[str, str] | None:
    """The meta table, None for a database without tables; raises for a foreign one."""
    try:
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    except sqlite3.DatabaseError as exc:
        raise IncompatibleStoreError(f"{p} cannot be read as a SQLite database ({exc}); it was "
                                     f"not changed. {_STORE_FIX}") from None
    if not tables:
        return None
    if "meta" not in tables or "runs" not in tables:
        raise IncompatibleStoreError(
            f"{p} is a SQLite database but not an emaphm campaign store (tables: "
            f"{', '.join(sorted(tables))}); it was not changed. {_STORE_FIX}")
    return {k: v for k, v in conn.execute("SELECT key, value FROM meta")}


def _check_schema(conn: sqlite3.Connection, meta: dict[str, str], p: Path) -> int:
    """The store's schema version (``user_version``; for version 2, ``meta.schema_version``),
    if this emaphm reads it; else an :class:`IncompatibleStoreError`."""
    user_version = int(conn.execute("PRAGMA user_version").fetchone()[0])
    version: Any = user_version if user_version else meta.get("schema_version")
    if str(version) == str(_META_VERSION) and not user_version and "spec_json" in meta:
        return _META_VERSION
    if version != SCHEMA_VERSION or "spec_json" not in meta:
        raise IncompatibleStoreError(
            f"{p} is a campaign store of schema version {version} written by emaphm "
            f"{meta.get('emaphm_version', '?')}; this emaphm ({__version__}) reads schema version "
            f"{SCHEMA_VERSION}. Open it with the emaphm version that wrote it, or start a new "
            "store; it was not changed.")
    return SCHEMA_VERSION


def _migrate_meta_version(conn: sqlite3.Connection) -> None:
    """A version-2 store to version 3: its number moves from ``meta.schema_version`` to
    ``user_version`` (the tables are the same), in one transaction."""
    conn.execute("BEGIN IMMEDIATE")
    try:
        if int(conn.execute("PRAGMA user_version").fetchone()[0]) == 0:
            conn.execute("DELETE FROM meta WHERE key = 'schema_version'")
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")


def _create(conn: sqlite3.Connection, spec: CampaignSpec) -> None:
    enable_wal(conn)
    conn.execute("BEGIN IMMEDIATE")
    try:
        for stmt in filter(None, (s.strip() for s in _SCHEMA.split(";"))):
            conn.execute(stmt)
        meta = {"emaphm_version": __version__, "spec_json": spec.to_json(),
                "spec_hash": spec.hash, "name": spec.name, "created_at": _now()}
        conn.executemany("INSERT OR IGNORE INTO meta (key, value) VALUES (?, ?)", meta.items())
        if int(conn.execute("PRAGMA user_version").fetchone()[0]) == 0:
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
    except BaseException:
        conn.execute("ROLLBACK")
        raise
    conn.execute("COMMIT")
