"""The trace container: :class:`Trace`, its columns and units, its JSON metadata, and
:func:`resample` (a trace on another time grid). Validation lives in
:mod:`emaphm.traces.validation`, the file formats in :mod:`emaphm.traces.files`."""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .derive import DERIVABLE, derive_missing, derived_meta

__all__ = ["COLUMNS", "OPTIONAL_COLUMNS", "DRIVE_COLUMNS", "DRIVE_GROUPS", "UNITS", "TraceError",
           "Trace", "resample", "fingerprint"]

COLUMNS: tuple[str, ...] = ("t", "theta_ref", "theta_m", "omega_m", "i_a", "i_b", "i_c")
#: What drives log, each optional: the phase voltages commanded for each control period
#: (star-referenced, ``v_a, v_b, v_c``), or the same in the dq frame (``v_d, v_q``: d along
#: the magnet's flux, amplitude invariant, :mod:`emaphm.models.inverter`), or the legs'
#: duty cycles ``d_a, d_b, d_c`` with the DC link ``v_dc``; the current references
#: ``i_d_ref, i_q_ref`` and the speed reference ``omega_ref``.
DRIVE_COLUMNS: tuple[str, ...] = ("v_a", "v_b", "v_c", "v_d", "v_q", "d_a", "d_b", "d_c", "v_dc",
                                  "i_d_ref", "i_q_ref", "omega_ref")
#: The drive signals that only come together: each group whole or not at all (``v_dc``
#: may come alone, ``i_d_ref`` only with ``i_q_ref``).
DRIVE_GROUPS: dict[str, tuple[str, ...]] = {
    "phase voltages": ("v_a", "v_b", "v_c"), "dq voltages": ("v_d", "v_q"),
    "duty cycles": ("d_a", "d_b", "d_c", "v_dc")}
OPTIONAL_COLUMNS: tuple[str, ...] = ("torque",) + DRIVE_COLUMNS
UNITS: dict[str, str] = {
    "t": "s",
    "theta_ref": "rad",
    "theta_m": "rad",
    "omega_m": "rad/s",
    "i_a": "A",
    "i_b": "A",
    "i_c": "A",
    "torque": "N m",
    **{f"v_{x}": "V" for x in "abcdq"},
    **{f"d_{x}": "1" for x in "abc"},
    "v_dc": "V",
    "i_d_ref": "A",
    "i_q_ref": "A",
    "omega_ref": "rad/s",
}


_FIELDS_1D = ("t", "theta_ref", "theta_m", "omega_m")


class TraceError(ValueError):
    """A trace, or a trace file, that cannot be used as it is.

    The message says what is wrong, where (column, first bad row and its time) and how to
    fix it.
    """


class TraceWarning(UserWarning):
    """A trace that was read, but not quite as written (its time shifted to start at 0),
    or that may not hold the whole test (shorter than its profile). The command line
    prints it as one line on stderr."""


def _expected_columns() -> str:
    req = ", ".join(f"{c} [{UNITS[c]}]" for c in COLUMNS)
    opt = ", ".join(f"{c} [{UNITS[c]}]" for c in OPTIONAL_COLUMNS)
    return f"{req} (optional: {opt})"


# --------------------------------------------------------------------------------------
# JSON metadata
# --------------------------------------------------------------------------------------


def _jsonable(obj: Any, where: str = "meta") -> Any:
    """Return ``obj`` as plain JSON types (dict with str keys, list, str, int, float, bool, None).

    numpy arrays become (nested) lists and numpy scalars Python scalars; tuples become
    lists; dataclass instances become dicts of their fields; paths become strings; enums
    their value. Anything else raises :class:`TraceError` naming the key path.
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return float(obj)
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in "biuf":
            raise TraceError(
                f"{where} is a numpy array of dtype {obj.dtype}, which cannot be stored as "
                "JSON metadata; store a real-valued array (or a list of str) instead"
            )
        return obj.tolist()
    if isinstance(obj, np.generic):
        if isinstance(obj, np.bool_):
            return bool(obj)
        if isinstance(obj, np.integer):
            return int(obj)
        if isinstance(obj, np.floating):
            return float(obj)
        if isinstance(obj, np.str_):
            return str(obj)
        raise TraceError(
            f"{where} is a numpy {type(obj).__name__}, which cannot be stored as JSON "
            "metadata; convert it to a float, int, str or bool"
        )
    if isinstance(obj, enum.Enum):
        return _jsonable(obj.value, where)
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        obj = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
    if isinstance(obj, Mapping):
        out = {}
        for key, value in obj.items():
            if not isinstance(key, str):
                raise TraceError(
                    f"{where} has the key {key!r} of type {type(key).__name__}; JSON "
                    f"metadata keys must be str, use {str(key)!r} instead"
                )
            out[key] = _jsonable(value, f"{where}[{key!r}]")
        return out
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v, f"{where}[{i}]") for i, v in enumerate(obj)]
    raise TraceError(
        f"{where} is a {type(obj).__module__}.{type(obj).__qualname__}, which cannot be "
        "stored as JSON metadata; store plain data instead (str, int, float, bool, None, "
        "lists, dicts with str keys, numpy arrays or scalars, dataclasses of those)"
    )


# --------------------------------------------------------------------------------------
# Trace
# --------------------------------------------------------------------------------------


def _as_readonly(name: str, value: Any, ndim: int) -> np.ndarray:
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and not value.flags.writeable:
        arr = value  # already frozen (e.g. taken from another Trace): share it
    else:
        try:
            arr = np.array(value, dtype=np.float64, copy=True)
        except (TypeError, ValueError) as exc:
            raise TraceError(
                f"Trace.{name} cannot be converted to a float64 array ({exc}); pass a "
                "real-valued numeric array"
            ) from None
        arr.setflags(write=False)
    if arr.ndim != ndim:
        shape = "(n,)" if ndim == 1 else "(n, 3)"
        raise TraceError(
            f"Trace.{name} has shape {arr.shape}, expected {shape}; pass a "
            f"{ndim}-D array"
        )
    return arr


@dataclass(frozen=True, eq=False)
class Trace:
    """Signals of one actuator run on one uniform time grid (SI units).

    ===========  ========  =======  ==============================================
    field        shape     unit     meaning
    ===========  ========  =======  ==============================================
    t            (n,)      s        time, uniform and strictly increasing
    theta_ref    (n,)      rad      position command
    theta_m      (n,)      rad      motor position
    omega_m      (n,)      rad/s    motor speed
    i_abc        (n, 3)    A        phase currents a, b, c
    torque       (n,)      N m      motor torque T_m, or None (measured traces)
    meta         dict               JSON metadata, see below
    drive        dict               the drive's own signals, by name (each (n,)):
                                    :data:`DRIVE_COLUMNS`, any of them, each group
                                    of :data:`DRIVE_GROUPS` whole; empty if none
    ===========  ========  =======  ==============================================

    Arrays are copied to float64 and made read-only (an input that already is a read-only
    float64 array is shared, not copied). Construction checks shapes only; use
    :func:`validate` for the physics checks.

    ``meta`` is normalised to plain JSON types on construction (numpy arrays -> lists,
    numpy scalars -> Python scalars, tuples -> lists, dataclasses -> dicts), so a trace
    and its written-and-read copy carry equal metadata. Conventional keys: ``"model"``
    (str), ``"k"`` (8 floats or None), ``"parameters"`` (nested dict), ``"profile"``
    (str or dict), ``"seed"`` (int or None), ``"units"`` (column -> unit string, checked
    by :func:`validate`); anything else is allowed.

    Two traces compare equal when all arrays are bitwise equal (NaN equal to NaN) and the
    metadata is equal.
    """

    t: np.ndarray
    theta_ref: np.ndarray
    theta_m: np.ndarray
    omega_m: np.ndarray
    i_abc: np.ndarray
    torque: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    drive: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in _FIELDS_1D:
            object.__setattr__(self, name, _as_readonly(name, getattr(self, name), 1))
        n = self.t.shape[0]
        for name in _FIELDS_1D[1:]:
            if getattr(self, name).shape != (n,):
                raise TraceError(
                    f"Trace.{name} has {getattr(self, name).shape[0]} samples but t has "
                    f"{n}; all signals must share the time grid t"
                )
        i_abc = _as_readonly("i_abc", self.i_abc, 2)
        if i_abc.shape != (n, 3):
            raise TraceError(
                f"Trace.i_abc has shape {i_abc.shape}, expected ({n}, 3) (one column per "
                "phase a, b, c, one row per sample of t); stack the phases with "
                "numpy.column_stack([i_a, i_b, i_c])"
            )
        object.__setattr__(self, "i_abc", i_abc)
        if self.torque is not None:
            torque = _as_readonly("torque", self.torque, 1)
            if torque.shape != (n,):
                raise TraceError(
                    f"Trace.torque has {torque.shape[0]} samples but t has {n}; pass a "
                    "torque sampled on t, or None"
                )
            object.__setattr__(self, "torque", torque)
        object.__setattr__(self, "drive", _drive_signals(self.drive, n))
        if not isinstance(self.meta, Mapping):
            raise TraceError(
                f"Trace.meta is a {type(self.meta).__name__}, expected a dict; pass e.g. "
                "meta={'model': 'reference'}"
            )
        object.__setattr__(self, "meta", _jsonable(self.meta))

    # ----------------------------------------------------------------------- properties
    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.shape[0])

    @property
    def dt(self) -> float:
        """Mean time step (t[-1] - t[0]) / (n - 1), s; NaN when n < 2."""
        if self.n < 2:
            return math.nan
        return float((self.t[-1] - self.t[0]) / (self.n - 1))

    @property
    def duration(self) -> float:
        """t[-1] - t[0], s (0 for fewer than two samples)."""
        if self.n < 2:
            return 0.0
        return float(self.t[-1] - self.t[0])

    @property
    def i_a(self) -> np.ndarray:
        """Phase current a, A (read-only view of ``i_abc[:, 0]``)."""
        return self.i_abc[:, 0]

    @property
    def i_b(self) -> np.ndarray:
        """Phase current b, A (read-only view of ``i_abc[:, 1]``)."""
        return self.i_abc[:, 1]

    @property
    def i_c(self) -> np.ndarray:
        """Phase current c, A (read-only view of ``i_abc[:, 2]``)."""
        return self.i_abc[:, 2]

    # -------------------------------------------------------------------------- helpers
    def columns(self) -> dict[str, np.ndarray]:
        """The signals as 1-D read-only arrays: :data:`COLUMNS` order, then ``torque`` if set,
        then the drive's signals in :data:`DRIVE_COLUMNS` order."""
        cols = {name: getattr(self, name) for name in COLUMNS}
        if self.torque is not None:
            cols["torque"] = self.torque
        cols.update((name, self.drive[name]) for name in DRIVE_COLUMNS if name in self.drive)
        return cols

    @classmethod
    def from_columns(cls, columns: Mapping[str, Any], meta: Mapping | None = None) -> Trace:
        """Build a trace from a mapping of column name -> 1-D array.

        Needs every name of :data:`COLUMNS` but those a recording may leave out: the speed
        ``omega_m`` and the third current ``i_c`` are derived where missing, as ``emaphm
        import`` derives them (:func:`emaphm.traces.derive.derive_missing`; the metadata
        says so: ``derived``, ``currents_measured: 2``). ``torque`` and the drive's signals
        (:data:`DRIVE_COLUMNS`) are used when present; other keys are ignored.
        """
        _require_columns(columns.keys(), derivable=True)
        if any(c not in columns for c in DERIVABLE):
            try:
                columns, notes = derive_missing(
                    {k: np.asarray(v, dtype=np.float64) for k, v in columns.items()},
                    np.asarray(columns["t"], dtype=np.float64))
            except (TypeError, ValueError) as exc:
                raise TraceError(f"the columns cannot be read as float64 arrays of one length "
                                 f"to derive {', '.join(c for c in DERIVABLE if c not in columns)} "
                                 f"({exc}); pass one array of shape (n,) per column") from None
            meta = derived_meta(meta or {}, notes)
        try:
            phases = [np.asarray(columns[p], dtype=np.float64) for p in ("i_a", "i_b", "i_c")]
        except (TypeError, ValueError) as exc:
            raise TraceError(
                f"phase current columns cannot be converted to float64 arrays ({exc}); "
                "pass real-valued numeric arrays"
            ) from None
        if any(p.ndim != 1 for p in phases) or len({p.shape for p in phases}) != 1:
            shapes = {p: np.shape(columns[p]) for p in ("i_a", "i_b", "i_c")}
            raise TraceError(
                f"phase current columns must be 1-D arrays of one length, got shapes "
                f"{shapes}; pass one array of shape (n,) per phase"
            )
        i_abc = np.column_stack(phases)
        return cls(
            t=columns["t"],
            theta_ref=columns["theta_ref"],
            theta_m=columns["theta_m"],
            omega_m=columns["omega_m"],
            i_abc=i_abc,
            torque=columns.get("torque"),
            meta=dict(meta) if meta is not None else {},
            drive={name: columns[name] for name in DRIVE_COLUMNS if name in columns},
        )

    def to_pandas(self):
        """The signals as a pandas DataFrame, one column per quantity (``t``, ``theta_ref``,
        ``theta_m``, ``omega_m``, ``i_a``, ``i_b``, ``i_c``, and ``torque`` and the drive's
        signals if set, SI units), the metadata in ``df.attrs["emaphm"]``. Needs pandas
        (``pip install 'emaphm[pandas]'``)."""
        from ..frames import require_pandas

        pd = require_pandas("Trace.to_pandas()")
        cols = self.columns()
        df = pd.DataFrame({k: np.array(v) for k, v in cols.items()})
        df.attrs["emaphm"] = json.loads(json.dumps(self.meta))
        return df

    @classmethod
    def from_pandas(cls, df: Any, meta: Mapping | None = None) -> Trace:
        """A trace from a DataFrame with the columns of :data:`COLUMNS` (SI units; others are
        ignored; ``omega_m`` and ``i_c`` derived where missing, as :meth:`from_columns`
        says), its metadata ``meta`` or else ``df.attrs["emaphm"]``."""
        if not hasattr(df, "columns") or not hasattr(df, "to_numpy"):
            raise TraceError(f"Trace.from_pandas() needs a pandas DataFrame, got {type(df).__name__}")
        names = [str(c) for c in df.columns]
        _require_columns(names, "DataFrame", derivable=True)
        if meta is None:
            meta = getattr(df, "attrs", {}).get("emaphm", {})
        try:
            cols = {c: df[c].to_numpy(dtype=np.float64) for c in COLUMNS + OPTIONAL_COLUMNS
                    if c in names}
        except (TypeError, ValueError) as exc:
            raise TraceError(f"DataFrame columns cannot be read as float64 ({exc}); give "
                             "numbers in SI units") from None
        return cls.from_columns(cols, meta=meta)

    def with_meta(self, **updates: Any) -> Trace:
        """A copy with ``meta`` updated by ``updates`` (arrays are shared, not copied)."""
        return dataclasses.replace(self, meta={**self.meta, **updates})

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Trace):
            return NotImplemented
        if (self.torque is None) != (other.torque is None) or set(self.drive) != set(other.drive):
            return False
        if not all(_bitwise_equal(a, other.drive[name]) for name, a in self.drive.items()):
            return False
        names = ("t", "theta_ref", "theta_m", "omega_m", "i_abc", "torque")
        for name in names:
            a, b = getattr(self, name), getattr(other, name)
            if a is None:
                continue
            if a.shape != b.shape or not _bitwise_equal(a, b):
                return False
        return json.dumps(self.meta, sort_keys=True) == json.dumps(other.meta, sort_keys=True)

    __hash__ = None  # type: ignore[assignment]  # holds arrays and a dict

    def __repr__(self) -> str:
        torque = "yes" if self.torque is not None else "no"
        drive = f", drive={list(self.drive)}" if self.drive else ""
        return (
            f"Trace(n={self.n}, dt={self.dt:.6g} s, duration={self.duration:.6g} s, "
            f"torque={torque}{drive}, meta keys={sorted(self.meta)})"
        )


def _drive_signals(drive: Any, n: int) -> dict[str, np.ndarray]:
    """The drive's signals of a trace of ``n`` samples, checked: known names, (n,) each,
    every group of :data:`DRIVE_GROUPS` whole."""
    if drive is None:
        return {}
    if not isinstance(drive, Mapping):
        raise TraceError(f"Trace.drive is a {type(drive).__name__}, expected a dict of the "
                         f"drive's signals by name ({', '.join(DRIVE_COLUMNS)})")
    unknown = sorted(set(drive) - set(DRIVE_COLUMNS))
    if unknown:
        raise TraceError(f"Trace.drive has unknown signal(s) {unknown}; a drive's signals are "
                         f"{', '.join(DRIVE_COLUMNS)} (SI units)")
    out = {}
    for name in DRIVE_COLUMNS:
        if name in drive and drive[name] is not None:
            arr = _as_readonly(name, drive[name], 1)
            if arr.shape != (n,):
                raise TraceError(f"Trace.drive['{name}'] has {arr.shape[0]} samples but t has "
                                 f"{n}; a drive signal is sampled on t")
            out[name] = arr
    for group, names in DRIVE_GROUPS.items():
        have = [x for x in names if x in out]
        if have and len(have) < len(names) and have != ["v_dc"]:
            missing = [x for x in names if x not in out]
            raise TraceError(f"the drive's {group} come together ({', '.join(names)}); the "
                             f"trace has {', '.join(have)} without {', '.join(missing)}: give "
                             "the whole group, or none of it")
    if "i_d_ref" in out and "i_q_ref" not in out:
        raise TraceError("the drive's current references: i_d_ref without i_q_ref; give i_q_ref "
                         "(i_d_ref is 0 when left out)")
    return out


def _bitwise_equal(a: np.ndarray, b: np.ndarray) -> bool:
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if not np.array_equal(nan_a, nan_b):
        return False
    keep = ~nan_a
    return bool(np.array_equal(a[keep].view(np.uint64), b[keep].view(np.uint64)))


def _require_columns(found: Any, source: str = "", *, derivable: bool = False) -> None:
    """A TraceError naming the columns of :data:`COLUMNS` missing from ``found`` (with
    ``derivable``, those :func:`~emaphm.traces.derive.derive_missing` can make are not
    missing where what they are made from is there)."""
    found = list(found)
    missing = [c for c in COLUMNS if c not in found and not (
        derivable and c in DERIVABLE and all(s in found for s in DERIVABLE[c]))]
    if missing:
        prefix = f"{source}: " if source else ""
        raise TraceError(
            f"{prefix}missing column(s) {missing}; found {found}. A trace needs the "
            f"columns {_expected_columns()}; rename the columns of the export to these "
            "names (units as given in brackets)"
            + ("; omega_m and i_c may be left out (derived from theta_m and t, and from i_a "
               "and i_b)" if derivable else "")
        )


# --------------------------------------------------------------------------------------
# Resampling
# --------------------------------------------------------------------------------------


def fingerprint(trace: Any) -> str:
    """SHA-256 (hex) of a trace's signals (t, theta_ref, theta_m, omega_m, i_abc) as
    little-endian float64: the same signals give the same fingerprint whatever the file
    format they were stored in (the health history recognises a trace it has seen by it;
    a calibration records those of its sources); the drive's signals, where a trace has
    them, after the rest."""
    h = hashlib.sha256(b"emaphm-trace-v1")
    drive = getattr(trace, "drive", None) or {}
    arrays = [(name, getattr(trace, name)) for name in ("t", "theta_ref", "theta_m", "omega_m",
                                                        "i_abc")]
    arrays += [(name, drive[name]) for name in DRIVE_COLUMNS if name in drive]
    for name, value in arrays:
        a = np.ascontiguousarray(np.asarray(value, dtype="<f8"))
        h.update(name.encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def resample(trace: Trace, t_new: Any) -> Trace:
    """Linearly interpolate every signal of ``trace`` onto the time grid ``t_new`` (s).

    ``t_new`` must be 1-D, finite, strictly increasing and lie inside
    ``[t[0], t[-1]]`` give or take half a mean step; points in that margin are
    extrapolated linearly from the end segment. ``trace.t`` must be strictly increasing
    (uniformity is not needed: this is how irregular bench traces are put on a uniform
    grid). The metadata is kept unchanged.
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"resample() needs a Trace, got {type(trace).__name__}")
    t = trace.t
    if trace.n < 2:
        raise TraceError(
            f"cannot resample a trace of {trace.n} sample(s); at least 2 are needed"
        )
    if not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0):
        raise TraceError(
            "cannot resample: trace.t must be finite and strictly increasing; sort the "
            "samples by time and drop duplicated or non-finite time stamps first"
        )
    try:
        t_new = np.array(t_new, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TraceError(f"t_new cannot be converted to a float64 array ({exc})") from None
    if t_new.ndim != 1 or t_new.shape[0] == 0:
        raise TraceError(f"t_new must be a non-empty 1-D array, got shape {t_new.shape}")
    if not np.all(np.isfinite(t_new)) or not np.all(np.diff(t_new) > 0):
        raise TraceError(
            "t_new must be finite and strictly increasing; build it with e.g. "
            "numpy.linspace(trace.t[0], trace.t[-1], n)"
        )
    half = 0.5 * trace.dt
    lo, hi = t[0] - half, t[-1] + half
    if t_new[0] < lo or t_new[-1] > hi:
        raise TraceError(
            f"t_new spans [{t_new[0]:.9g}, {t_new[-1]:.9g}] s, outside the trace "
            f"[{t[0]:.9g}, {t[-1]:.9g}] s (tolerance half a step, {half:.3g} s); "
            "resampling does not extrapolate, keep t_new inside the recorded time"
        )
    idx = np.clip(np.searchsorted(t, t_new, side="right") - 1, 0, trace.n - 2)
    t0, t1 = t[idx], t[idx + 1]
    w = ((t_new - t0) / (t1 - t0))[:, None]
    drive = [name for name in DRIVE_COLUMNS if name in trace.drive]
    signals = np.column_stack(
        [trace.theta_ref, trace.theta_m, trace.omega_m, trace.i_abc]
        + ([trace.torque] if trace.torque is not None else [])
        + [trace.drive[name] for name in drive]
    )
    y0, y1 = signals[idx], signals[idx + 1]
    out = np.where(w == 1.0, y1, y0 + w * (y1 - y0))
    first = 7 if trace.torque is not None else 6
    return Trace(
        t=t_new,
        theta_ref=out[:, 0],
        theta_m=out[:, 1],
        omega_m=out[:, 2],
        i_abc=out[:, 3:6],
        torque=out[:, 6] if trace.torque is not None else None,
        meta=trace.meta,
        drive={name: out[:, first + j] for j, name in enumerate(drive)},
    )
