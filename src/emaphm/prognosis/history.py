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
ID``), a time that does not move forward or lies outside :data:`MAX_TIME`, a trace
already recorded, a store that cannot be written (a read-only file or folder).

Reading: ``readonly=True`` opens the file with SQLite's ``mode=ro`` and changes nothing
(no byte of the file, no journal file left behind), also on a read-only file or in a
read-only folder; :meth:`HealthHistory.data` gives the analyses (trends, figures, the
fleet site) only the inspections they can use and names the others
(:class:`SkippedInspection`): a record written by an older version with a time such as
1e308, a non-finite k or a malformed field is skipped, not a crash, and can be taken back
with :meth:`HealthHistory.remove`.

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
import json
import math
import os
import re
import sqlite3
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from .._files import folder_problem, regular_file
from .._sqlite import (SQLITE_HEADER, connect_readonly, enable_wal, journal_files,
                       remove_journal_files, store_name_problem, write_problem)
from .._text import shown, utf8_text
from ..faults import as_k
from ..traces import fingerprint

__all__ = ["SCHEMA_VERSION", "TIME_UNITS", "MAX_TIME", "HistoryError", "UnknownActuatorError",
           "TimeOrderError", "DuplicateInspectionError", "ReadOnlyHistoryError", "Actuator",
           "Inspection", "HistoryData", "SkippedInspection", "RemovedInspection",
           "CalibrationRecord", "HealthHistory", "trace_fingerprint", "DEFAULT_DB",
           "check_registration"]

SCHEMA_VERSION = 3
TIME_UNITS = ("h", "cycles")

#: Latest time a history holds, per time unit (times start at 0, entry into service).
#: 1e6 flight hours is 114 years without a stop, ten times the longest airframe design
#: life (about 1e5 h); 1e9 cycles is one cycle a second for 30 years, above any
#: actuator's rated cycle life. A time beyond it is a typing error (1e308), and every
#: time within it keeps the trends' arithmetic well inside double precision.
MAX_TIME = {"h": 1e6, "cycles": 1e9}

_UNIT_WORDS = {"h": "flight hours", "cycles": "cycles"}

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
    readings TEXT NOT NULL DEFAULT '{}',
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


class ReadOnlyHistoryError(HistoryError):
    """The store cannot be written (a read-only file or folder); it was not changed."""


#: The latest time of an actuator's inspections, numbers only (a time stored as text by
#: another program is not a time).
_LAST_TIME = "max(CASE WHEN typeof(i.time) IN ('real', 'integer') THEN i.time END)"


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

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Actuator":
        """The actuator :meth:`to_dict` wrote."""
        return cls(**dict(data))


@dataclass(frozen=True)
class Inspection:
    """One recorded inspection (results as data).

    ``k``, ``k_lo``, ``k_hi`` (8,): identified fault vector and its interval
    (``spread_method`` at probability ``level``); ``diagnosis`` the
    :meth:`emaphm.diagnosis.Diagnosis.to_dict`; ``fingerprint`` the SHA-256
    of the trace's signals (:func:`trace_fingerprint`); ``source`` where the
    trace came from (a path); ``extra`` free JSON; ``readings`` the health indicators
    beyond k as the inspection measured them (:func:`emaphm.modes.indicator_readings`:
    name -> value, None where it did not).
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
    readings: dict = field(default_factory=dict)

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

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Inspection":
        """The record :meth:`to_dict` wrote (``fault_model`` is read from ``extra``)."""
        d = {k: v for k, v in data.items() if k != "fault_model"}
        for name in ("k", "k_lo", "k_hi"):
            d[name] = np.asarray(d[name], dtype=float)
        d["extra"] = dict(d.get("extra") or {})
        d["readings"] = dict(d.get("readings") or {})
        return cls(**d)


@dataclass(frozen=True)
class SkippedInspection:
    """A stored inspection the analyses cannot use: its ``id``, ``time`` (NaN where it is
    unreadable), when it was recorded and the ``reason``. :meth:`HealthHistory.remove`
    takes it back by id."""

    id: int
    actuator: str
    time: float
    recorded_utc: str | None
    reason: str

    def to_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["time"] = self.time if math.isfinite(self.time) else str(self.time)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "SkippedInspection":
        """The record :meth:`to_dict` wrote (KeyError, TypeError or ValueError when ``d``
        is not one)."""
        return cls(id=int(d["id"]), actuator=str(d["actuator"]), time=float(d["time"]),
                   recorded_utc=d.get("recorded_utc"), reason=str(d["reason"]))


@dataclass(frozen=True)
class RemovedInspection:
    """What :meth:`HealthHistory.remove` took out of the store, as it was stored."""

    id: int
    actuator: str
    time: float
    recorded_utc: str | None
    verdict: str | None
    source: str | None

    def to_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["time"] = self.time if math.isfinite(self.time) else str(self.time)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "RemovedInspection":
        """The record :meth:`to_dict` wrote."""
        return cls(id=int(d["id"]), actuator=str(d["actuator"]), time=float(d["time"]),
                   recorded_utc=d.get("recorded_utc"), verdict=d.get("verdict"),
                   source=d.get("source"))


@dataclass(frozen=True)
class HistoryData:
    """An actuator's k history as arrays: ``times`` (n,), ``K``, ``K_lo``, ``K_hi`` (n, 8),
    of the inspections the analyses can use; ``skipped`` names the others
    (:class:`SkippedInspection`)."""

    actuator: Actuator
    times: np.ndarray
    K: np.ndarray
    K_lo: np.ndarray
    K_hi: np.ndarray
    inspections: tuple
    skipped: tuple = ()

    @property
    def n(self) -> int:
        return int(self.times.size)

    @property
    def observed(self) -> dict[str, np.ndarray]:
        """Health indicator -> which inspections could see its fault mode (a boolean mask
        over ``times``): False where the drive path the inspection was identified on
        could not (its record's ``extra["not_observable"]``, e.g. the gain drift k8 from
        recorded voltages, where no position loop is modelled; its k there is a
        placeholder). :func:`~emaphm.prognosis.trends.prognose` trends the others only."""
        from .thresholds import INDICATOR_MODE

        blind = [frozenset((i.extra or {}).get("not_observable") or ()) for i in self.inspections]
        return {n: np.fromiter((m not in b for b in blind), dtype=bool, count=len(blind))
                for n, m in INDICATOR_MODE.items()}

    @property
    def readings(self) -> dict[str, np.ndarray]:
        """Health indicator beyond k -> its readings over ``times`` (NaN where an inspection
        did not measure it: :attr:`Inspection.readings`), for each indicator measured at
        one inspection at least (one no inspection measured has no series: a prognosis
        leaves it out as it leaves out one it is not given)."""
        from ..modes import INDICATORS

        out = {}
        for n, ind in INDICATORS.items():
            if ind.reading is None:
                continue
            r = np.array([_reading(i.readings.get(n)) for i in self.inspections], dtype=float)
            if np.isfinite(r).any():
                out[n] = r
        return out

    def skipped_note(self) -> str | None:
        """One sentence on the inspections left out of the analyses (None when none was):
        how many, the first ones by id and time, why, and how to take them back."""
        return skipped_note(self.actuator, self.skipped)


def skipped_note(actuator: Actuator, skipped: Sequence[SkippedInspection]) -> str | None:
    """:meth:`HistoryData.skipped_note` (also for several actuators' records at once)."""
    if not skipped:
        return None
    shown_ = "; ".join(f"id {s.id} at {_fmt(s.time)} {actuator.time_unit}: {s.reason}"
                       for s in skipped[:3])
    more = f"; and {len(skipped) - 3} more" if len(skipped) > 3 else ""
    n = len(skipped)
    how = (f"--id {skipped[0].id}" if n == 1 else f"--id ID, one at a time (e.g. --id {skipped[0].id})")
    return (f"left out {n} stored inspection{'s' if n != 1 else ''} of {actuator.id} that "
            f"cannot be used ({shown_}{more}); take {'them' if n != 1 else 'it'} back with "
            f"emaphm history remove {actuator.id} {how}")


def _fmt(t: float) -> str:
    """A time as it was given: every digit a float holds (587.7000001 is not 587.7), no
    exponent below 1e16."""
    return f"{t:.15g}" if isinstance(t, (int, float)) else repr(t)


@dataclass(frozen=True)
class CalibrationRecord:
    """A recorded calibration: the actuator's ``params`` (:class:`emaphm.params.ActuatorParams`)
    from ``time`` on, the ``sources`` (trace paths) it was fitted on, when it was recorded."""

    actuator: str
    time: float
    params: Any
    sources: tuple
    recorded_utc: str


#: SHA-256 of a trace's signals (:func:`emaphm.traces.fingerprint`): an inspection's trace
#: recognised whatever file held it.
trace_fingerprint = fingerprint


def _vec(x: Any, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (8,) or not np.all(np.isfinite(a)):
        raise HistoryError(f"{name} must be 8 finite numbers, got {x!r}")
    return a


def check_registration(actuator_id: Any, time_unit: Any = "h") -> None:
    """A :class:`HistoryError` for an actuator id or a time unit :meth:`HealthHistory.register`
    refuses, checked before a history file is created."""
    if not isinstance(actuator_id, str) or not _ID.fullmatch(actuator_id):
        raise HistoryError(f"actuator id {shown(actuator_id)} must be 1-64 characters of letters, "
                           "digits and . _ : / - starting with a letter or digit, e.g. "
                           "EMA-0042")
    if time_unit not in TIME_UNITS:
        raise HistoryError(f"time unit {time_unit!r} unknown; choose one of "
                           f"{', '.join(TIME_UNITS)} (flight hours or cycles)")


def _json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, allow_nan=False, default=_json_default)


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


def _other_store(tables: Any) -> str:
    """What other emaphm store the tables ``tables`` make ("" where none): a campaign store
    (its runs), an assessment's (its units)."""
    names = set(tables or ())
    if {"meta", "runs"} <= names:
        return "an emaphm campaign store (emaphm campaign, emaphm report read it)"
    if {"meta", "units"} <= names:
        return "an emaphm assessment's store of units (emaphm assess resumes from it)"
    return ""


class HealthHistory:
    """An SQLite health-history store (module docstring). Use as a context manager.

    ``create=False`` opens an existing database only (for commands that record into a
    registered actuator): a missing or empty file raises :class:`HistoryError` instead of
    becoming a database. ``readonly=True`` (for commands that only read) opens an existing
    history with SQLite's ``mode=ro``: nothing is written, migrated or left behind, and a
    read-only file or folder is fine. A history that cannot be written is refused up front
    by a writing open (:class:`ReadOnlyHistoryError`), before any work.
    """

    def __init__(self, path: str | os.PathLike[str], *, create: bool = True,
                 readonly: bool = False, timeout_s: float = 30.0) -> None:
        problem = store_name_problem(path)
        if problem is not None:
            raise HistoryError(f"--db {shown(os.fspath(path))} {problem}; give the path of a "
                               "health history file, e.g. --db fleet.sqlite")
        self.path = Path(path)
        self.readonly = bool(readonly)
        create = create and not readonly
        exists = os.path.lexists(self.path)        # a link loop or a dangling link is there
        if exists:
            regular_file(self.path, "health history", error=HistoryError, missing=HistoryError,
                         give="the path of a health history file")
        elif not create:
            raise HistoryError(f"no health history at {self.path}; register an actuator first "
                               f"(emaphm history register ID --db {self.path})")
        else:
            if not self.path.parent.exists():
                raise HistoryError(f"cannot create the health history {self.path}: folder "
                                   f"{self.path.parent} does not exist; create it first")
            problem = folder_problem(self.path.parent)
            if problem is not None:
                raise ReadOnlyHistoryError(
                    f"cannot create the health history {self.path}: cannot write in the folder "
                    f"{self.path.parent} ({problem}); give a --db in a folder you can write to")
        if exists and not create:
            self._check_file()
        if exists and not self.readonly:
            problem = write_problem(self.path)
            if problem is not None:
                raise ReadOnlyHistoryError(self._readonly_message(problem))
        self._has_calibrations = True
        self._has_readings = True
        created = journal_files(self.path) if exists else []
        try:
            self._open(create, timeout_s)
        except BaseException:
            remove_journal_files(created)          # a refused file is left as it was found
            raise
        self._created = created if self.readonly else []

    def _check_file(self) -> None:
        """An existing file that a reading open takes for a history: not empty, SQLite."""
        with open(self.path, "rb") as fh:
            header = fh.read(len(SQLITE_HEADER))
        if not header:
            raise HistoryError(f"{self.path} is an empty file, not a health history; it was "
                               "not changed. Register an actuator to start one (emaphm history "
                               f"register ID --db {self.path}) or give another --db path")
        if header != SQLITE_HEADER:
            raise HistoryError(f"{self.path} is not an emaphm health history (not an SQLite "
                               "database); it was not changed. Give another --db path")

    def _readonly_message(self, problem: str) -> str:
        return (f"cannot write the health history {self.path}: {problem}; it was not changed. "
                "Make it writable (e.g. chmod u+w) or work on a copy you can write (--db COPY); "
                "history show, list, prognose and fleet report read it as it is")

    def _open(self, create: bool, timeout_s: float) -> None:
        try:
            self._con = (connect_readonly(self.path, timeout_s) if self.readonly else
                         sqlite3.connect(str(self.path), timeout=timeout_s, isolation_level=None))
        except sqlite3.DatabaseError as exc:
            raise HistoryError(self._foreign(exc)) from None
        try:
            version, tables = self._version()
            if version > 0:          # an existing history: refuse a damaged file up front
                self._quick_check()
            names = {r[0] for r in self._con.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table'")} if tables else set()
            other = _other_store(names)
            if other and "actuators" not in names:
                raise HistoryError(f"{self.path} is {other}, not a health history; it was not "
                                   "changed. Give the health history's --db path")
            if version > SCHEMA_VERSION:
                raise HistoryError(f"{self.path} has schema version {version}, newer than this "
                                   f"emaphm understands ({SCHEMA_VERSION}); upgrade emaphm")
            if version == 0 and tables:
                raise HistoryError(f"{self.path} is an SQLite database but not an emaphm health "
                                   "history; it was not changed. Give another --db path")
            if version == 0 and not create:
                raise HistoryError(f"{self.path} is an empty SQLite database, not a health "
                                   "history; it was not changed. Register an actuator to start "
                                   f"one (emaphm history register ID --db {self.path})")
            if self.readonly:
                self.journal_mode = str(self._con.execute("PRAGMA journal_mode").fetchone()[0])
                self._has_calibrations = version >= 2
                self._has_readings = version >= 3
                return
            self._con.execute("PRAGMA foreign_keys = ON")
            self.journal_mode = enable_wal(self._con, timeout_s)
            self._con.execute("PRAGMA synchronous = FULL")
            self._migrate(version)
        except sqlite3.OperationalError as exc:
            self._con.close()
            if "readonly" in str(exc):
                raise ReadOnlyHistoryError(self._readonly_message(str(exc))) from None
            raise HistoryError(self._foreign(exc)) from None
        except sqlite3.DatabaseError as exc:
            self._con.close()
            raise HistoryError(self._foreign(exc)) from None
        except BaseException:
            self._con.close()
            raise

    def _foreign(self, exc: Exception) -> str:
        if "malformed" in str(exc):             # an SQLite file, cut or overwritten in part
            return (f"{self.path} is damaged ({exc}); it was not changed. Restore it from a "
                    "backup; nothing is read from or added to a damaged history")
        return f"{self.path} is not an emaphm health history ({exc}); give another --db path"

    def _version(self) -> tuple[int, int]:
        version = int(self._con.execute("PRAGMA user_version").fetchone()[0])
        tables = int(self._con.execute("SELECT count(*) FROM sqlite_master").fetchone()[0])
        return version, tables

    def _quick_check(self) -> None:
        try:
            check = str(self._con.execute("PRAGMA quick_check").fetchone()[0])
        except sqlite3.DatabaseError as exc:
            check = str(exc)
        if check != "ok":
            raise HistoryError(f"{self.path} is damaged (SQLite quick_check: {check[:200]}); "
                               "it was not changed. Restore it from a backup; nothing is read "
                               "from or added to a damaged history")

    def _migrate(self, version: int) -> None:
        """Create the schema in a new file, or bring an older one to :data:`SCHEMA_VERSION`
        (each step in one transaction, re-read inside it: another process may have won)."""
        if version == 0:
            with self._transaction() as con:
                if con.execute("PRAGMA user_version").fetchone()[0] == 0:
                    if con.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]:
                        raise HistoryError(
                            f"{self.path} is an SQLite database but not an emaphm health "
                            "history; give another --db path")
                    for statement in _statements(_SCHEMA):
                        con.execute(statement)
                    con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
        elif version < SCHEMA_VERSION:
            with self._transaction() as con:
                now = con.execute("PRAGMA user_version").fetchone()[0]
                if now == 1:                         # before calibrations were recorded
                    for statement in _statements(_SCHEMA):
                        if statement.startswith("CREATE TABLE calibrations"):
                            con.execute(statement)
                if now in (1, 2):                    # before the readings beyond k
                    if "readings" not in {r[1] for r in con.execute(
                            "PRAGMA table_info(inspections)")}:
                        con.execute("ALTER TABLE inspections ADD COLUMN readings TEXT NOT NULL "
                                    "DEFAULT '{}'")
                    _fill_readings(con)
                if now < SCHEMA_VERSION:
                    con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")

    # ------------------------------------------------------------------ plumbing
    def close(self) -> None:
        self._con.close()
        remove_journal_files(self._created)     # a read-only open leaves nothing behind
        self._created = []

    def __enter__(self) -> "HealthHistory":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    class _Tx:
        def __init__(self, history: "HealthHistory") -> None:
            self.con = history._con
            self.history = history

        def __enter__(self) -> sqlite3.Connection:
            if self.history.readonly:
                raise HistoryError(f"{self.history.path} was opened read-only; open it with "
                                   "readonly=False to record")
            try:
                self.con.execute("BEGIN IMMEDIATE")
            except sqlite3.OperationalError as exc:
                self._readonly(exc)
                raise
            return self.con

        def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
            if exc_type is None:
                try:
                    self.con.execute("COMMIT")
                except sqlite3.OperationalError as err:
                    self.con.execute("ROLLBACK")
                    self._readonly(err)
                    raise
            else:
                self.con.execute("ROLLBACK")
                if isinstance(exc, sqlite3.OperationalError):
                    self._readonly(exc)

        def _readonly(self, exc: Exception) -> None:
            """SQLite refused to write (a file or folder made read-only while open, a
            read-only connection): the file and the permission, in the history's words."""
            if "readonly" in str(exc):
                raise ReadOnlyHistoryError(self.history._readonly_message(str(exc))) from None

    def _transaction(self) -> "HealthHistory._Tx":
        return HealthHistory._Tx(self)

    def integrity_check(self) -> str:
        """SQLite's ``PRAGMA integrity_check`` (``"ok"`` when sound)."""
        return str(self._con.execute("PRAGMA integrity_check").fetchone()[0])

    # ------------------------------------------------------------------ calibrations
    def calibrate(self, actuator_id: str, time: float, params: Any,
                  sources: Sequence[str] = ()) -> None:
        """Record that ``actuator_id`` was (re)calibrated at ``time`` to ``params``
        (:class:`emaphm.params.ActuatorParams`, e.g. from :func:`emaphm.calibration.calibrate`);
        its inspections from then on are diagnosed with them by default."""
        t = float(self.check_time(actuator_id, time, "calibration time"))
        with self._transaction() as con:
            con.execute("INSERT INTO calibrations (actuator, time, params, sources, recorded_utc) "
                        "VALUES (?, ?, ?, ?, ?)",
                        (actuator_id, t, _json(params.to_dict()),
                         _json([utf8_text(str(s)) for s in sources]), _now()))

    def calibration(self, actuator_id: str, at: float | None = None) -> tuple[float, Any] | None:
        """``(time, params)`` of the latest calibration of ``actuator_id`` at or before
        ``at`` (the latest of all without ``at``), or None if it was never calibrated."""
        from ..params import ActuatorParams

        self.actuator(actuator_id)
        if not self._has_calibrations:                 # a version-1 store, read as it is
            return None
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
        if not self._has_calibrations:
            return []
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
        check_registration(actuator_id, time_unit)
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
            "SELECT a.id, a.description, a.time_unit, a.created_utc, count(i.id), " + _LAST_TIME + " "
            "FROM actuators a LEFT JOIN inspections i ON i.actuator = a.id "
            "GROUP BY a.id ORDER BY a.id").fetchall()
        return [Actuator(*r) for r in rows]

    def actuator(self, actuator_id: str) -> Actuator:
        """The registered actuator ``actuator_id`` (or :class:`UnknownActuatorError`)."""
        row = self._con.execute(
            "SELECT a.id, a.description, a.time_unit, a.created_utc, count(i.id), " + _LAST_TIME + " "
            "FROM actuators a LEFT JOIN inspections i ON i.actuator = a.id WHERE a.id = ? "
            "GROUP BY a.id", (actuator_id,)).fetchone()
        if row is None:
            known = [a.id for a in self.actuators()]
            hint = f" (registered: {', '.join(known[:10])}{'...' if len(known) > 10 else ''})" \
                if known else " (none registered yet)"
            raise UnknownActuatorError(
                f"actuator {shown(actuator_id)} is not registered in {self.path}{hint}"
                + (f"; to record it, register it first (emaphm history register {actuator_id} "
                   f"--db {self.path}); emaphm history list --db {self.path} lists the others"
                   if isinstance(actuator_id, str) and _ID.fullmatch(actuator_id) else
                   "; an actuator id is 1-64 characters of letters, digits and . _ : / -"))
        return Actuator(*row)

    # ------------------------------------------------------------------ inspections
    def check_next(self, actuator_id: str, time: float, fingerprint: str | None = None) -> Actuator:
        """Raise unless an inspection of ``actuator_id`` at ``time`` could be recorded now
        (cheap: run it before an identification)."""
        return self._check(self._con, actuator_id, time, fingerprint)

    def check_time(self, actuator_id: str, time: Any, what: str = "inspection time") -> float:
        """``time`` as a float if it is a time ``actuator_id``'s history can hold: a finite
        number from 0 to :data:`MAX_TIME` of its time unit (else :class:`HistoryError`)."""
        if isinstance(time, bool) or not isinstance(time, (int, float, np.integer, np.floating)) \
                or not math.isfinite(time) or time < 0:
            raise HistoryError(f"{what} must be a finite number >= 0 (flight hours or "
                               f"cycles), got {time!r}")
        unit = self.actuator(actuator_id).time_unit
        limit = MAX_TIME.get(unit, MAX_TIME["h"])
        if time > limit:
            raise HistoryError(
                f"{what} {float(time):g} {unit} is beyond the {limit:g} {_UNIT_WORDS.get(unit, unit)} "
                f"a history holds; give the actuator's {_UNIT_WORDS.get(unit, unit)} since it "
                "entered service, e.g. --at 1250")
        return float(time)

    def _check(self, con: sqlite3.Connection, actuator_id: str, time: Any,
               fingerprint: str | None) -> Actuator:
        self.check_time(actuator_id, time)
        act = self.actuator(actuator_id)
        if act.last_time is not None and not float(time) > act.last_time:
            limit = MAX_TIME.get(act.time_unit, MAX_TIME["h"])
            hint = ("(give the time of this inspection with --at)" if act.last_time <= limit else
                    f"(its last time is beyond the {limit:g} {act.time_unit} a history holds: "
                    f"take that inspection back with emaphm history remove {actuator_id} --at "
                    f"{act.last_time!r})")
            raise TimeOrderError(
                f"inspection time {float(time):g} {act.time_unit} of {actuator_id!r} is not after "
                f"its last inspection at {act.last_time:g} {act.time_unit}; times must increase "
                + hint)
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
            extra: dict | None = None, readings: Mapping[str, float | None] | None = None
            ) -> Inspection:
        """Record one inspection in one transaction; on any error nothing is recorded.

        ``k`` (8 values in [0, 1]); ``k_lo``/``k_hi`` its interval (default ``k``);
        ``readings``: the health indicators beyond k (name -> value, None where not
        measured), by default read from ``diagnosis`` and ``extra``
        (:func:`emaphm.modes.indicator_readings`).
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
        read = _readings(diagnosis, extra, readings)
        try:
            payload = (_json(kk.tolist()), _json(lo.tolist()), _json(hi.tolist()),
                       None if diagnosis is None else _json(diagnosis), _json(extra or {}),
                       _json(read))
        except (TypeError, ValueError) as exc:
            raise HistoryError(f"cannot record the inspection: {exc}") from None
        try:
            with self._transaction() as con:
                self._check(con, actuator_id, time, fingerprint)
                cur = con.execute(
                    "INSERT INTO inspections (actuator, time, k, k_lo, k_hi, spread_method, level, "
                    "healthy, diagnosis, fingerprint, algorithm, seed, fitness, evaluations, "
                    "source, recorded_utc, extra, readings) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
                    "?, ?, ?, ?, ?, ?, ?, ?)",
                    (actuator_id, float(time), payload[0], payload[1], payload[2], spread_method,
                     None if level is None else float(level),
                     None if healthy is None else int(healthy), payload[3], fingerprint,
                     algorithm, None if seed is None else int(seed),
                     None if fitness is None else float(fitness),
                     None if evaluations is None else int(evaluations),
                     None if source is None else utf8_text(str(source)), _now(), payload[4],
                     payload[5]))
                row_id = cur.lastrowid
                self._touch(con, actuator_id)
        except sqlite3.IntegrityError as exc:       # the schema's own guard (e.g. a racing writer)
            raise HistoryError(f"inspection refused by the store: {exc}") from None
        return self._inspection(row_id)

    def _touch(self, con: sqlite3.Connection, actuator_id: str) -> None:
        con.execute("UPDATE actuators SET updated_utc = ? WHERE id = ?", (_now(), actuator_id))

    _COLS = ("id, actuator, time, k, k_lo, k_hi, spread_method, level, healthy, diagnosis, "
             "fingerprint, algorithm, seed, fitness, evaluations, source, recorded_utc, extra")

    @property
    def _cols(self) -> str:
        """The columns an inspection is read from (a history opened read-only before its
        migration to schema 3 has no readings: they are read from its diagnoses)."""
        return self._COLS + (", readings" if self._has_readings else ", NULL")

    @staticmethod
    def _row(r: Sequence[Any]) -> Inspection:
        diagnosis = None if r[9] is None else json.loads(r[9])
        extra = json.loads(r[17])
        readings = json.loads(r[18]) if r[18] is not None else _readings(diagnosis, extra, None)
        if not isinstance(readings, dict):
            raise ValueError(f"readings are not a JSON object: {str(r[18])[:40]}")
        return Inspection(
            id=r[0], actuator=r[1], time=float(r[2]), k=np.array(json.loads(r[3])),
            k_lo=np.array(json.loads(r[4])), k_hi=np.array(json.loads(r[5])),
            spread_method=r[6], level=r[7], healthy=None if r[8] is None else bool(r[8]),
            diagnosis=diagnosis, fingerprint=r[10],
            algorithm=r[11], seed=r[12], fitness=r[13], evaluations=r[14], source=r[15],
            recorded_utc=r[16], extra=extra, readings=readings)

    def _inspection(self, row_id: int) -> Inspection:
        r = self._con.execute(f"SELECT {self._cols} FROM inspections WHERE id = ?", (row_id,)).fetchone()
        return self._row(r)

    def _read(self, actuator_id: str) -> tuple[list[Inspection], list[SkippedInspection]]:
        """The actuator's inspections in time order that the analyses can use, and the
        others with the reason (:func:`_unusable`)."""
        unit = self.actuator(actuator_id).time_unit
        good: list[Inspection] = []
        skipped: list[SkippedInspection] = []
        for r in self._iter(actuator_id):
            try:
                ins = self._row(r)
            except (TypeError, ValueError, OverflowError, RecursionError) as exc:
                why = f"unreadable record ({type(exc).__name__}: {str(exc)[:80]})"
                skipped.append(SkippedInspection(int(r[0]), actuator_id, _as_time(r[2]),
                                                 _as_text(r[16]), why))
                continue
            why = _unusable(ins, unit)
            if why is None:
                good.append(ins)
            else:
                skipped.append(SkippedInspection(ins.id, actuator_id, ins.time, _as_text(r[16]), why))
        return good, skipped

    def inspections(self, actuator_id: str) -> list[Inspection]:
        """The inspections of ``actuator_id`` in time order (those the analyses can use:
        :meth:`data` names the others)."""
        return self._read(actuator_id)[0]

    def remove(self, actuator_id: str, *, at: float | None = None,
               inspection_id: int | None = None) -> RemovedInspection:
        """Take back one recorded inspection of ``actuator_id``: the one at time ``at`` or
        the one with id ``inspection_id`` (give one of the two), in one transaction; return
        what was removed. A :class:`HistoryError` when none matches (nothing changes)."""
        if (at is None) == (inspection_id is None):
            raise HistoryError("say which inspection to remove: its time (--at T) or its id (--id N)")
        act = self.actuator(actuator_id)
        if at is not None:
            where, arg, which = "time = ?", float(at), f"at {_fmt(float(at))} {act.time_unit}"
        else:
            where, arg, which = "id = ?", int(inspection_id), f"with id {inspection_id}"
        with self._transaction() as con:
            row = con.execute("SELECT id, time, recorded_utc, healthy, diagnosis, source FROM "
                              f"inspections WHERE actuator = ? AND {where}",
                              (actuator_id, arg)).fetchone()
            if row is None:
                known = con.execute("SELECT id, time FROM inspections WHERE actuator = ? ORDER BY "
                                    "time LIMIT 8", (actuator_id,)).fetchall()
                listed = ", ".join(f"id {i} at {_fmt(_as_time(t))}" for i, t in known)
                raise HistoryError(
                    f"{actuator_id} has no inspection {which}; nothing was removed"
                    + (f" (its inspections: {listed}{', ...' if len(known) == 8 else ''}; "
                       f"emaphm history show {actuator_id} lists them)" if known else
                       " (it has no inspections)"))
            con.execute("DELETE FROM inspections WHERE id = ?", (row[0],))
            self._touch(con, actuator_id)
        return RemovedInspection(id=int(row[0]), actuator=actuator_id, time=_as_time(row[1]),
                                 recorded_utc=_as_text(row[2]), verdict=_verdict_of(row[3], row[4]),
                                 source=_as_text(row[5]))

    def _iter(self, actuator_id: str) -> Iterator[Sequence[Any]]:
        return iter(self._con.execute(
            f"SELECT {self._cols} FROM inspections WHERE actuator = ? ORDER BY time",
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

    def record_digests(self) -> dict[str, str] | None:
        """SHA-256 of each actuator's records as the store holds them (its row, its
        inspections and calibrations, every column), read in one pass in one snapshot
        without decoding any: what tells a reader (the fleet site's cache) that an
        actuator is unchanged, cheaply on a large fleet. None where the file cannot be
        read that way (the caller then keys each actuator by :meth:`data`)."""
        import hashlib

        try:
            con = connect_readonly(self.path, 30.0)
        except (sqlite3.Error, OSError):
            return None
        hashes: dict[Any, Any] = {}
        try:
            con.execute("BEGIN")                   # the three tables as of one moment
            tables = {r[0] for r in con.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table'")}
            for table, owner in (("actuators", "id"), ("inspections", "actuator"),
                                 ("calibrations", "actuator")):
                if table not in tables:
                    continue
                for row in con.execute(f"SELECT {owner}, * FROM {table} ORDER BY {owner}, rowid"):
                    h = hashes.get(row[0])
                    if h is None:
                        h = hashes[row[0]] = hashlib.sha256()
                    h.update(f"{table}\x00{row[1:]!r}\x00".encode("utf-8", "surrogatepass"))
        except sqlite3.Error:
            return None
        finally:
            con.close()
        return {str(k): v.hexdigest() for k, v in hashes.items()}

    def data(self, actuator_id: str) -> HistoryData:
        """The k history of ``actuator_id`` as arrays (:class:`HistoryData`): the
        inspections the analyses can use, and in ``skipped`` the others (a time outside
        0 to :data:`MAX_TIME`, a k that is not 8 finite numbers in [0, 1], a malformed
        field), which the trends, figures and the fleet site leave out."""
        act = self.actuator(actuator_id)
        ins, skipped = self._read(actuator_id)
        if ins:
            K = np.stack([i.k for i in ins])
            lo = np.stack([i.k_lo for i in ins])
            hi = np.stack([i.k_hi for i in ins])
        else:
            K = lo = hi = np.empty((0, 8))
        return HistoryData(actuator=act, times=np.array([i.time for i in ins], dtype=float),
                           K=K, K_lo=lo, K_hi=hi, inspections=tuple(ins), skipped=tuple(skipped))


def _readings(diagnosis: Any, extra: Any, given: Mapping[str, Any] | None) -> dict[str, float | None]:
    """The readings an inspection stores: ``given`` checked (known indicators beyond k,
    finite numbers or None), else read from its diagnosis and record."""
    from ..modes import INDICATORS, indicator_readings

    if given is None:
        return indicator_readings(diagnosis, extra)
    out: dict[str, float | None] = {}
    for name, v in given.items():
        if name not in INDICATORS or INDICATORS[name].reading is None:
            raise HistoryError(f"cannot record the inspection: readings: {shown(name)} is not a "
                               "health indicator beyond k; choose from " + ", ".join(
                                   n for n, i in INDICATORS.items() if i.reading is not None))
        if v is not None and not (isinstance(v, (int, float)) and not isinstance(v, bool)
                                  and math.isfinite(v)):
            raise HistoryError(f"cannot record the inspection: readings[{name!r}] must be a "
                               f"finite number or None (not measured), got {v!r}")
        out[name] = None if v is None else float(v)
    return out


def _fill_readings(con: sqlite3.Connection) -> None:
    """Schema 2 to 3: each stored inspection's readings beyond k from its diagnosis and
    record, where they have them (a record that cannot be read keeps none)."""
    rows = con.execute("SELECT id, diagnosis, extra FROM inspections").fetchall()
    for row_id, diagnosis, extra in rows:
        try:
            d = None if diagnosis is None else json.loads(diagnosis)
            e = json.loads(extra) if isinstance(extra, str) else {}
        except (TypeError, ValueError, RecursionError):
            d, e = None, {}
        con.execute("UPDATE inspections SET readings = ? WHERE id = ?",
                    (_json(_readings(d, e, None)), row_id))


def _reading(x: Any) -> float:
    """A stored reading as a number, NaN where it is missing or not a finite number."""
    try:
        v = float(x)
    except (TypeError, ValueError, OverflowError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def _as_time(x: Any) -> float:
    try:
        return float(x)
    except (TypeError, ValueError, OverflowError):
        return math.nan


def _as_text(x: Any) -> str | None:
    return None if x is None else str(x)


def _verdict_of(healthy: Any, diagnosis: Any) -> str | None:
    try:
        verdict = json.loads(diagnosis).get("verdict") if diagnosis else None
    except (TypeError, ValueError, AttributeError, RecursionError):
        verdict = None
    if isinstance(verdict, str):
        return verdict
    return None if healthy is None else ("healthy" if healthy else "faulty")


def _unusable(ins: Inspection, unit: str) -> str | None:
    """Why the analyses cannot use a stored inspection, or None: its time outside 0 to
    :data:`MAX_TIME` of the unit, k and its interval not 8 finite numbers (k in [0, 1]),
    a diagnosis that is not an object with a list of fault objects, extra not an object."""
    limit = MAX_TIME.get(unit, MAX_TIME["h"])
    if not (math.isfinite(ins.time) and 0.0 <= ins.time <= limit):
        return f"time outside 0 to {limit:g} {unit}"
    for name in ("k", "k_lo", "k_hi"):
        v = getattr(ins, name)
        if v.shape != (8,) or v.dtype.kind not in "biuf" or not np.all(np.isfinite(v)):
            return f"{name} is not 8 finite numbers"
    if np.any((ins.k < 0.0) | (ins.k > 1.0)):
        return "k outside [0, 1]"
    diag = ins.diagnosis
    if diag is not None and (not isinstance(diag, dict) or not isinstance(diag.get("faults", []), list)
                             or not all(isinstance(f, dict) for f in diag.get("faults", []))):
        return "malformed diagnosis"
    if not isinstance(ins.extra, dict):
        return "malformed extra field"
    return None


def __getattr__(name: str):
    """``emaphm.prognosis.history.inspect`` of version 0.3, kept for one release with a
    warning: the workflow lives in :mod:`emaphm.prognosis.workflow` (the store only stores)."""
    if name == "inspect":
        import warnings

        from .workflow import record_inspection as inspect

        warnings.warn("emaphm.prognosis.history.inspect moved to emaphm.prognosis.workflow."
                      "record_inspection (also emaphm.prognosis.record_inspection); the old name "
                      "goes in the next release",
                      DeprecationWarning, stacklevel=2)
        return inspect
    raise AttributeError(f"module 'emaphm.prognosis.history' has no attribute {name!r}")
