"""Health history: an embedded SQLite store of inspections per actuator.

One database file holds any number of actuators. Each inspection records the
actuator, its time (flight hours or cycles, fixed per actuator), the identified
``k`` with its interval, the diagnosis, the identification's settings and the
fingerprint of the trace it came from.

Durability and integrity:

* write-ahead log (``journal_mode=WAL``) with ``synchronous=FULL``: a committed
  inspection survives a crash of the process or of the machine;
* one transaction per inspection (``BEGIN IMMEDIATE`` ... ``COMMIT``): an
  inspection is in the store entirely or not at all, and two writers never
  interleave;
* the rules are checked inside that transaction, and again by the schema
  (foreign key to ``actuators``, ``UNIQUE(actuator, time)``, a trigger that
  refuses a time not after the actuator's last one), so a refused inspection
  leaves the history exactly as it was.

Errors are :class:`HistoryError` (a ``ValueError``) with a message that says
what to do: an unknown actuator (register it first: ``emaphm history register
ID``), a time that does not move forward, a trace already recorded.

Schema (``PRAGMA user_version = 2``; a version-1 store gains the calibrations table
when opened)::

    actuators(id TEXT PRIMARY KEY, description TEXT, time_unit TEXT, created_utc TEXT,
              updated_utc TEXT)
    inspections(id INTEGER PRIMARY KEY, actuator TEXT REFERENCES actuators(id),
                time REAL, k TEXT, k_lo TEXT, k_hi TEXT  -- JSON lists of 8 floats
                spread_method TEXT, level REAL, healthy INTEGER, diagnosis TEXT (JSON),
                fingerprint TEXT, algorithm TEXT, seed INTEGER, fitness REAL,
                evaluations INTEGER, source TEXT, recorded_utc TEXT, extra TEXT (JSON),
                UNIQUE(actuator, time))
    calibrations(id INTEGER PRIMARY KEY, actuator TEXT REFERENCES actuators(id),
                 time REAL, params TEXT (JSON, ActuatorParams.to_dict), sources TEXT (JSON),
                 recorded_utc TEXT)
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import re
import sqlite3
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Sequence

import numpy as np

from .._sqlite import enable_wal, journal_files, remove_journal_files
from .._text import shown
from ..faults import as_k

__all__ = ["SCHEMA_VERSION", "TIME_UNITS", "HistoryError", "UnknownActuatorError",
           "TimeOrderError", "DuplicateInspectionError", "Actuator", "Inspection", "HistoryData",
           "CalibrationRecord", "HealthHistory", "trace_fingerprint", "DEFAULT_DB"]

SCHEMA_VERSION = 2
TIME_UNITS = ("h", "cycles")

#: Database used by the CLI when neither ``--db`` nor ``$EMAPHM_HISTORY`` names one.
DEFAULT_DB = "emaphm-history.sqlite"

_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._:/-]{0,63}")

_SCHEMA = """
CREATE TABLE actuators (
    id TEXT PRIMARY KEY,
    description TEXT NOT NULL DEFAULT '',
    time_unit TEXT NOT NULL CHECK (time_unit IN ('h', 'cycles')),
    created_utc TEXT NOT NULL,
    updated_utc TEXT NOT NULL
);
CREATE TABLE inspections (
    id INTEGER PRIMARY KEY,
    actuator TEXT NOT NULL REFERENCES actuators(id),
    time REAL NOT NULL CHECK (time >= 0),
    k TEXT NOT NULL,
    k_lo TEXT NOT NULL,
    k_hi TEXT NOT NULL,
    spread_method TEXT,
    level REAL,
    healthy INTEGER,
    diagnosis TEXT,
    fingerprint TEXT,
    algorithm TEXT,
    seed INTEGER,
    fitness REAL,
    evaluations INTEGER,
    source TEXT,
    recorded_utc TEXT NOT NULL,
    extra TEXT NOT NULL DEFAULT '{}',
    UNIQUE (actuator, time)
);
CREATE INDEX inspections_fingerprint ON inspections(actuator, fingerprint);
CREATE TABLE calibrations (
    id INTEGER PRIMARY KEY,
    actuator TEXT NOT NULL REFERENCES actuators(id),
    time REAL NOT NULL CHECK (time >= 0),
    params TEXT NOT NULL,
    sources TEXT NOT NULL DEFAULT '[]',
    recorded_utc TEXT NOT NULL
);
CREATE TRIGGER inspections_time_forward BEFORE INSERT ON inspections
WHEN NEW.time <= (SELECT MAX(time) FROM inspections WHERE actuator = NEW.actuator)
BEGIN
    SELECT RAISE(ABORT, 'inspection time must be after the last inspection of this actuator');
END;
"""


def _statements(script: str) -> list[str]:
    """Split an SQL script into complete statements (executescript would commit first)."""
    out, buf = [], ""
    for line in script.splitlines(keepends=True):
        buf += line
        if sqlite3.complete_statement(buf):
            out.append(buf.strip())
            buf = ""
    return out


class HistoryError(ValueError):
    """A health-history operation was refused; the store is unchanged."""


class UnknownActuatorError(HistoryError):
    """The actuator is not registered in the store."""


class TimeOrderError(HistoryError):
    """An inspection's time is not after the actuator's last inspection."""


class DuplicateInspectionError(HistoryError):
    """The same trace is already recorded for this actuator."""


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="microseconds")


@dataclass(frozen=True)
class Actuator:
    """A registered actuator: ``id``, ``description``, ``time_unit`` (``"h"`` or
    ``"cycles"``), ``created_utc``, ``n_inspections``, ``last_time`` (None if none)."""

    id: str
    description: str
    time_unit: str
    created_utc: str
    n_inspections: int = 0
    last_time: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class Inspection:
    """One recorded inspection (results as data).

    ``k``, ``k_lo``, ``k_hi`` (8,): identified fault vector and its interval
    (``spread_method`` at probability ``level``); ``diagnosis`` the
    :meth:`emaphm.diagnosis.Diagnosis.to_dict`; ``fingerprint`` the SHA-256
    of the trace's signals (:func:`trace_fingerprint`); ``source`` where the
    trace came from (a path); ``extra`` free JSON.
    """

    id: int
    actuator: str
    time: float
    k: np.ndarray
    k_lo: np.ndarray
    k_hi: np.ndarray
    spread_method: str | None
    level: float | None
    healthy: bool | None
    diagnosis: dict | None
    fingerprint: str | None
    algorithm: str | None
    seed: int | None
    fitness: float | None
    evaluations: int | None
    source: str | None
    recorded_utc: str
    extra: dict = field(default_factory=dict)

    @property
    def fault_model(self) -> str:
        """The fault model the inspection was diagnosed with (``"paper"`` for inspections
        recorded before fault models existed)."""
        fm = (self.extra or {}).get("fault_model")
        return fm if isinstance(fm, str) else "paper"

    def to_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["fault_model"] = self.fault_model
        for name in ("k", "k_lo", "k_hi"):
            d[name] = [float(x) for x in d[name]]
        return d


@dataclass(frozen=True)
class HistoryData:
    """An actuator's k history as arrays: ``times`` (n,), ``K``, ``K_lo``, ``K_hi`` (n, 8)."""

    actuator: Actuator
    times: np.ndarray
    K: np.ndarray
    K_lo: np.ndarray
    K_hi: np.ndarray
    inspections: tuple

    @property
    def n(self) -> int:
        return int(self.times.size)


@dataclass(frozen=True)
class CalibrationRecord:
    """A recorded calibration: the actuator's ``params`` (:class:`emaphm.params.ActuatorParams`)
    from ``time`` on, the ``sources`` (trace paths) it was fitted on, when it was recorded."""

    actuator: str
    time: float
    params: Any
    sources: tuple
    recorded_utc: str


def trace_fingerprint(trace: Any) -> str:
    """SHA-256 (hex) of a trace's signals (t, theta_ref, theta_m, omega_m, i_abc), as
    little-endian float64: the same signals give the same fingerprint whatever the file
    format they were stored in."""
    h = hashlib.sha256(b"emaphm-trace-v1")
    for name in ("t", "theta_ref", "theta_m", "omega_m", "i_abc"):
        a = np.ascontiguousarray(np.asarray(getattr(trace, name), dtype="<f8"))
        h.update(name.encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _vec(x: Any, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (8,) or not np.all(np.isfinite(a)):
        raise HistoryError(f"{name} must be 8 finite numbers, got {x!r}")
    return a


def _json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, allow_nan=False, default=_json_default)


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


class HealthHistory:
    """An SQLite health-history store (module docstring). Use as a context manager.

    ``create=False`` opens an existing database only (for reading commands):
    a missing file raises :class:`HistoryError` instead of creating one.
    """

    def __init__(self, path: str | os.PathLike[str], *, create: bool = True,
                 timeout_s: float = 30.0) -> None:
        self.path = Path(path)
        if not create and not self.path.exists():
            raise HistoryError(f"no health history at {self.path}; register an actuator first "
                               f"(emaphm history register ID --db {self.path})")
        if create and not self.path.parent.exists():
            raise HistoryError(f"cannot create the health history {self.path}: folder "
                               f"{self.path.parent} does not exist; create it first")
        created = journal_files(self.path) if self.path.exists() else []
        try:
            self._con = sqlite3.connect(str(self.path), timeout=timeout_s, isolation_level=None)
        except sqlite3.DatabaseError as exc:
            raise HistoryError(f"{self.path} is not an emaphm health history ({exc}); "
                               "give another --db path") from None
        try:
            self._con.execute("PRAGMA foreign_keys = ON")
            mode = enable_wal(self._con, timeout_s)
            self._con.execute("PRAGMA synchronous = FULL")
            version = self._con.execute("PRAGMA user_version").fetchone()[0]
        except sqlite3.DatabaseError as exc:
            self._con.close()
            remove_journal_files(created)       # a refused file is left as it was found
            if "malformed" in str(exc):         # an SQLite file, cut or overwritten in part
                raise HistoryError(f"{self.path} is damaged ({exc}); it was not changed. "
                                   "Restore it from a backup; nothing is read from or added "
                                   "to a damaged history") from None
            raise HistoryError(f"{self.path} is not an emaphm health history ({exc}); "
                               "give another --db path") from None
        self.journal_mode = str(mode)
        if version > 0:                # an existing history: refuse a damaged file up front
            try:
                check = str(self._con.execute("PRAGMA quick_check").fetchone()[0])
            except sqlite3.DatabaseError as exc:
                check = str(exc)
            if check != "ok":
                self._con.close()
                remove_journal_files(created)
                raise HistoryError(f"{self.path} is damaged (SQLite quick_check: {check[:200]}); "
                                   "it was not changed. Restore it from a backup; nothing is read "
                                   "from or added to a damaged history")
        if version == 0:
            try:
                with self._transaction() as con:     # re-read: another process may have won
                    if con.execute("PRAGMA user_version").fetchone()[0] == 0:
                        if con.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]:
                            raise HistoryError(
                                f"{self.path} is an SQLite database but not an emaphm health "
                                "history; give another --db path")
                        for statement in _statements(_SCHEMA):
                            con.execute(statement)
                        con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            except HistoryError:
                self._con.close()
                raise
        elif version == 1:                           # before calibrations were recorded
            with self._transaction() as con:
                if con.execute("PRAGMA user_version").fetchone()[0] == 1:
                    for statement in _statements(_SCHEMA):
                        if statement.startswith("CREATE TABLE calibrations"):
                            con.execute(statement)
                    con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
        elif version > SCHEMA_VERSION:
            self._con.close()
            raise HistoryError(f"{self.path} has schema version {version}, newer than this "
                               f"emaphm understands ({SCHEMA_VERSION}); upgrade emaphm")

    # ------------------------------------------------------------------ plumbing
    def close(self) -> None:
        self._con.close()

    def __enter__(self) -> "HealthHistory":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    class _Tx:
        def __init__(self, con: sqlite3.Connection) -> None:
            self.con = con

        def __enter__(self) -> sqlite3.Connection:
            self.con.execute("BEGIN IMMEDIATE")
            return self.con

        def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
            if exc_type is None:
                self.con.execute("COMMIT")
            else:
                self.con.execute("ROLLBACK")

    def _transaction(self) -> "HealthHistory._Tx":
        return HealthHistory._Tx(self._con)

    def integrity_check(self) -> str:
        """SQLite's ``PRAGMA integrity_check`` (``"ok"`` when sound)."""
        return str(self._con.execute("PRAGMA integrity_check").fetchone()[0])

    # ------------------------------------------------------------------ calibrations
    def calibrate(self, actuator_id: str, time: float, params: Any,
                  sources: Sequence[str] = ()) -> None:
        """Record that ``actuator_id`` was (re)calibrated at ``time`` to ``params``
        (:class:`emaphm.params.ActuatorParams`, e.g. from :func:`emaphm.calibration.calibrate`);
        its inspections from then on are diagnosed with them by default."""
        self.actuator(actuator_id)
        t = float(time)
        if not (math.isfinite(t) and t >= 0):
            raise HistoryError(f"calibration time must be a finite number >= 0, got {time!r}")
        with self._transaction() as con:
            con.execute("INSERT INTO calibrations (actuator, time, params, sources, recorded_utc) "
                        "VALUES (?, ?, ?, ?, ?)",
                        (actuator_id, t, _json(params.to_dict()),
                         _json([str(s) for s in sources]), _now()))

    def calibration(self, actuator_id: str, at: float | None = None) -> tuple[float, Any] | None:
        """``(time, params)`` of the latest calibration of ``actuator_id`` at or before
        ``at`` (the latest of all without ``at``), or None if it was never calibrated."""
        from ..params import ActuatorParams

        self.actuator(actuator_id)
        q = "SELECT time, params FROM calibrations WHERE actuator = ?"
        args: list[Any] = [actuator_id]
        if at is not None:
            q += " AND time <= ?"
            args.append(float(at))
        row = self._con.execute(q + " ORDER BY time DESC, id DESC LIMIT 1", args).fetchone()
        if row is None:
            return None
        return float(row[0]), ActuatorParams.from_dict(json.loads(row[1]),
                                                       source=f"calibration of {actuator_id}")

    def calibrations(self, actuator_id: str) -> list[CalibrationRecord]:
        """Every calibration of ``actuator_id``, in time order."""
        from ..params import ActuatorParams

        self.actuator(actuator_id)
        rows = self._con.execute("SELECT time, params, sources, recorded_utc FROM calibrations "
                                 "WHERE actuator = ? ORDER BY time, id", (actuator_id,)).fetchall()
        return [CalibrationRecord(actuator=actuator_id, time=float(t),
                                  params=ActuatorParams.from_dict(
                                      json.loads(p), source=f"calibration of {actuator_id}"),
                                  sources=tuple(str(x) for x in json.loads(src)), recorded_utc=rec)
                for t, p, src, rec in rows]

    # ------------------------------------------------------------------ actuators
    def register(self, actuator_id: str, *, description: str = "", time_unit: str = "h") -> Actuator:
        """Register a new actuator; its inspections are then timed in ``time_unit``."""
        if not isinstance(actuator_id, str) or not _ID.fullmatch(actuator_id):
            raise HistoryError(f"actuator id {shown(actuator_id)} must be 1-64 characters of letters, "
                               "digits and . _ : / - starting with a letter or digit, e.g. "
                               "EMA-0042")
        if time_unit not in TIME_UNITS:
            raise HistoryError(f"time unit {time_unit!r} unknown; choose one of "
                               f"{', '.join(TIME_UNITS)} (flight hours or cycles)")
        now = _now()
        try:
            with self._transaction() as con:
                con.execute("INSERT INTO actuators (id, description, time_unit, created_utc, "
                            "updated_utc) VALUES (?, ?, ?, ?, ?)",
                            (actuator_id, str(description), time_unit, now, now))
        except sqlite3.IntegrityError:
            raise HistoryError(f"actuator {actuator_id!r} is already registered in {self.path}; "
                               "record its inspections with emaphm history add") from None
        return self.actuator(actuator_id)

    def actuators(self) -> list[Actuator]:
        """Every registered actuator, by id."""
        rows = self._con.execute(
            "SELECT a.id, a.description, a.time_unit, a.created_utc, count(i.id), max(i.time) "
            "FROM actuators a LEFT JOIN inspections i ON i.actuator = a.id "
            "GROUP BY a.id ORDER BY a.id").fetchall()
        return [Actuator(*r) for r in rows]

    def actuator(self, actuator_id: str) -> Actuator:
        """The registered actuator ``actuator_id`` (or :class:`UnknownActuatorError`)."""
        row = self._con.execute(
            "SELECT a.id, a.description, a.time_unit, a.created_utc, count(i.id), max(i.time) "
            "FROM actuators a LEFT JOIN inspections i ON i.actuator = a.id WHERE a.id = ? "
            "GROUP BY a.id", (actuator_id,)).fetchone()
        if row is None:
            known = [a.id for a in self.actuators()]
            hint = f" (registered: {', '.join(known[:10])}{'...' if len(known) > 10 else ''})" \
                if known else " (none registered yet)"
            raise UnknownActuatorError(
                f"actuator {shown(actuator_id)} is not registered in {self.path}{hint}"
                + (f"; register it first: emaphm history register {actuator_id} --db {self.path}"
                   if isinstance(actuator_id, str) and _ID.fullmatch(actuator_id) else
                   "; an actuator id is 1-64 characters of letters, digits and . _ : / -"))
        return Actuator(*row)

    # ------------------------------------------------------------------ inspections
    def check_next(self, actuator_id: str, time: float, fingerprint: str | None = None) -> Actuator:
        """Raise unless an inspection of ``actuator_id`` at ``time`` could be recorded now
        (cheap: run it before an identification)."""
        return self._check(self._con, actuator_id, time, fingerprint)

    def _check(self, con: sqlite3.Connection, actuator_id: str, time: Any,
               fingerprint: str | None) -> Actuator:
        if isinstance(time, bool) or not isinstance(time, (int, float, np.integer, np.floating)) \
                or not math.isfinite(time) or time < 0:
            raise HistoryError(f"inspection time must be a finite number >= 0 (flight hours or "
                               f"cycles), got {time!r}")
        act = self.actuator(actuator_id)
        if act.last_time is not None and not float(time) > act.last_time:
            raise TimeOrderError(
                f"inspection time {float(time):g} {act.time_unit} of {actuator_id!r} is not after "
                f"its last inspection at {act.last_time:g} {act.time_unit}; times must increase "
                "(give the time of this inspection with --at)")
        if fingerprint is not None:
            row = con.execute("SELECT time FROM inspections WHERE actuator = ? AND fingerprint = ?",
                              (actuator_id, fingerprint)).fetchone()
            if row is not None:
                raise DuplicateInspectionError(
                    f"this trace (fingerprint {fingerprint[:12]}...) is already recorded for "
                    f"{actuator_id!r} at {row[0]:g} {act.time_unit}; record a new measurement")
        return act

    def add(self, actuator_id: str, time: float, k: Any, *, k_lo: Any = None, k_hi: Any = None,
            spread_method: str | None = None, level: float | None = None,
            diagnosis: dict | None = None, fingerprint: str | None = None,
            algorithm: str | None = None, seed: int | None = None, fitness: float | None = None,
            evaluations: int | None = None, source: str | None = None,
            extra: dict | None = None) -> Inspection:
        """Record one inspection in one transaction; on any error nothing is recorded.

        ``k`` (8 values in [0, 1]); ``k_lo``/``k_hi`` its interval (default ``k``).
        """
        try:
            kk = as_k(k)
        except ValueError as exc:
            raise HistoryError(f"cannot record the inspection: {exc}") from None
        lo = kk.copy() if k_lo is None else _vec(k_lo, "k_lo")
        hi = kk.copy() if k_hi is None else _vec(k_hi, "k_hi")
        if np.any(lo > kk + 1e-12) or np.any(hi < kk - 1e-12):
            raise HistoryError("the interval [k_lo, k_hi] must contain k")
        healthy = None if diagnosis is None else bool(diagnosis.get("healthy"))
        try:
            payload = (_json(kk.tolist()), _json(lo.tolist()), _json(hi.tolist()),
                       None if diagnosis is None else _json(diagnosis), _json(extra or {}))
        except (TypeError, ValueError) as exc:
            raise HistoryError(f"cannot record the inspection: {exc}") from None
        try:
            with self._transaction() as con:
                self._check(con, actuator_id, time, fingerprint)
                cur = con.execute(
                    "INSERT INTO inspections (actuator, time, k, k_lo, k_hi, spread_method, level, "
                    "healthy, diagnosis, fingerprint, algorithm, seed, fitness, evaluations, "
                    "source, recorded_utc, extra) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
                    "?, ?, ?, ?)",
                    (actuator_id, float(time), payload[0], payload[1], payload[2], spread_method,
                     None if level is None else float(level),
                     None if healthy is None else int(healthy), payload[3], fingerprint,
                     algorithm, None if seed is None else int(seed),
                     None if fitness is None else float(fitness),
                     None if evaluations is None else int(evaluations),
                     None if source is None else str(source), _now(), payload[4]))
                row_id = cur.lastrowid
                self._touch(con, actuator_id)
        except sqlite3.IntegrityError as exc:       # the schema's own guard (e.g. a racing writer)
            raise HistoryError(f"inspection refused by the store: {exc}") from None
        return self._inspection(row_id)

    def _touch(self, con: sqlite3.Connection, actuator_id: str) -> None:
        con.execute("UPDATE actuators SET updated_utc = ? WHERE id = ?", (_now(), actuator_id))

    _COLS = ("id, actuator, time, k, k_lo, k_hi, spread_method, level, healthy, diagnosis, "
             "fingerprint, algorithm, seed, fitness, evaluations, source, recorded_utc, extra")

    @staticmethod
    def _row(r: Sequence[Any]) -> Inspection:
        return Inspection(
            id=r[0], actuator=r[1], time=float(r[2]), k=np.array(json.loads(r[3])),
            k_lo=np.array(json.loads(r[4])), k_hi=np.array(json.loads(r[5])),
            spread_method=r[6], level=r[7], healthy=None if r[8] is None else bool(r[8]),
            diagnosis=None if r[9] is None else json.loads(r[9]), fingerprint=r[10],
            algorithm=r[11], seed=r[12], fitness=r[13], evaluations=r[14], source=r[15],
            recorded_utc=r[16], extra=json.loads(r[17]))

    def _inspection(self, row_id: int) -> Inspection:
        r = self._con.execute(f"SELECT {self._COLS} FROM inspections WHERE id = ?", (row_id,)).fetchone()
        return self._row(r)

    def inspections(self, actuator_id: str) -> list[Inspection]:
        """The inspections of ``actuator_id`` in time order."""
        self.actuator(actuator_id)
        return [self._row(r) for r in self._iter(actuator_id)]

    def _iter(self, actuator_id: str) -> Iterator[Sequence[Any]]:
        return iter(self._con.execute(
            f"SELECT {self._COLS} FROM inspections WHERE actuator = ? ORDER BY time",
            (actuator_id,)).fetchall())

    def frame(self, actuator_id: str):
        """The actuator's inspections as a pandas DataFrame, one row per inspection in time
        order: ``time`` (in the actuator's time unit), ``k_<name>``, ``k_lo_<name>`` and
        ``k_hi_<name>`` per component (:data:`emaphm.faults.K_NAMES`), ``verdict``,
        ``healthy``, ``fault_model``, ``algorithm``, ``seed``, ``fitness``,
        ``evaluations``, ``spread_method``, ``level``, ``fingerprint``, ``source``,
        ``recorded_utc``; indexed by the inspection id. Needs pandas."""
        from ..faults import K_NAMES
        from ..frames import require_pandas, vector_columns

        pd = require_pandas("HealthHistory.frame()")
        rows = []
        for ins in self.inspections(actuator_id):
            row: dict[str, Any] = {"id": ins.id, "time": ins.time}
            vector_columns(row, "k", ins.k, K_NAMES)
            vector_columns(row, "k_lo", ins.k_lo, K_NAMES)
            vector_columns(row, "k_hi", ins.k_hi, K_NAMES)
            verdict = (ins.diagnosis or {}).get("verdict") if isinstance(ins.diagnosis, dict) else None
            row.update(verdict=verdict, healthy=ins.healthy, fault_model=ins.fault_model,
                       algorithm=ins.algorithm, seed=ins.seed, fitness=ins.fitness,
                       evaluations=ins.evaluations, spread_method=ins.spread_method,
                       level=ins.level, fingerprint=ins.fingerprint, source=ins.source,
                       recorded_utc=ins.recorded_utc)
            rows.append(row)
        columns = ["id", "time"] + [f"{p}_{n}" for p in ("k", "k_lo", "k_hi") for n in K_NAMES] + [
            "verdict", "healthy", "fault_model", "algorithm", "seed", "fitness", "evaluations",
            "spread_method", "level", "fingerprint", "source", "recorded_utc"]
        df = pd.DataFrame(rows, columns=columns).set_index("id")
        df.attrs["actuator"] = self.actuator(actuator_id).to_dict()
        return df

    def data(self, actuator_id: str) -> HistoryData:
        """The k history of ``actuator_id`` as arrays (:class:`HistoryData`)."""
        act = self.actuator(actuator_id)
        ins = self.inspections(actuator_id)
        if ins:
            K = np.stack([i.k for i in ins])
            lo = np.stack([i.k_lo for i in ins])
            hi = np.stack([i.k_hi for i in ins])
        else:
            K = lo = hi = np.empty((0, 8))
        return HistoryData(actuator=act, times=np.array([i.time for i in ins], dtype=float),
                           K=K, K_lo=lo, K_hi=hi, inspections=tuple(ins))


def __getattr__(name: str):
    """``emaphm.prognosis.history.inspect`` of version 0.3, kept for one release with a
    warning: the workflow lives in :mod:`emaphm.prognosis.workflow` (the store only stores)."""
    if name == "inspect":
        import warnings

        from .workflow import inspect

        warnings.warn("emaphm.prognosis.history.inspect moved to emaphm.prognosis.workflow.inspect "
                      "(also emaphm.prognosis.inspect); the old name goes in the next release",
                      DeprecationWarning, stacklevel=2)
        return inspect
    raise AttributeError(f"module 'emaphm.prognosis.history' has no attribute {name!r}")
