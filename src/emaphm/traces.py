"""Measured or simulated actuator traces: container, CSV/Parquet I/O and validation.

A :class:`Trace` holds what the diagnosis needs from one run of the actuator, sampled on
one uniform time grid. Every quantity is SI:

==========  =======  ===========================================
column      unit     meaning
==========  =======  ===========================================
t           s        time, uniform and strictly increasing
theta_ref   rad      position command (motor side)
theta_m     rad      motor position
omega_m     rad/s    motor speed, d(theta_m)/dt
i_a         A        phase current a
i_b         A        phase current b
i_c         A        phase current c
torque      N m      motor torque T_m (optional, simulations only)
==========  =======  ===========================================

File formats (chosen by suffix, see :func:`write_trace` / :func:`read_trace`):

* ``.csv``: first line ``# emaphm-trace 1 {json metadata}``, then a header row with the
  column names, then one comma-separated row per sample written with ``repr`` of each
  float (shortest exact round trip). The reader also accepts bench exports without the
  metadata line: columns in any order, extra columns ignored, ``;`` or tab delimiters,
  names written as ``name [unit]`` and an optional units row such as ``[s],[rad],...``.
* ``.parquet``: one float64 column per quantity; the metadata JSON is stored in the schema
  metadata under the key ``b"emaphm"``.

Writes are atomic: the file is written to a temporary sibling and moved over the target
with :func:`os.replace`, so a failure never leaves a half-written file.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
import os
import re
import warnings
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from ._files import atomic_write

__all__ = [
    "COLUMNS",
    "OPTIONAL_COLUMNS",
    "UNITS",
    "MIN_SAMPLES",
    "SUFFIXES",
    "TraceError",
    "Trace",
    "validate",
    "write_trace",
    "read_trace",
    "resample",
]

COLUMNS: tuple[str, ...] = ("t", "theta_ref", "theta_m", "omega_m", "i_a", "i_b", "i_c")
OPTIONAL_COLUMNS: tuple[str, ...] = ("torque",)
UNITS: dict[str, str] = {
    "t": "s",
    "theta_ref": "rad",
    "theta_m": "rad",
    "omega_m": "rad/s",
    "i_a": "A",
    "i_b": "A",
    "i_c": "A",
    "torque": "N m",
}

#: Fewest samples :func:`validate` accepts.
MIN_SAMPLES = 100
#: File suffixes understood by :func:`write_trace` and :func:`read_trace`.
SUFFIXES: tuple[str, ...] = (".csv", ".parquet")
#: Format version written in the CSV first line and the Parquet schema metadata.
FORMAT_VERSION = 1

_CSV_MAGIC = "# emaphm-trace"
_PARQUET_META_KEY = b"emaphm"
_PARQUET_VERSION_KEY = b"emaphm-trace"

# Unit heuristics of validate().
_MAX_TIME_STEP = 0.01  # s; a larger step suggests milliseconds
_MAX_DURATION = 1e3  # s; a longer trace suggests milliseconds
_MAX_CURRENT = 1e3  # A; a larger current suggests milliamperes
_MIN_SPEED_CORRELATION = 0.9  # omega_m vs d(theta_m)/dt must be this collinear to judge units
_RATIO_TOLERANCE = 0.10  # relative distance of a speed ratio to a known factor
_RATIO_BAND = (0.5, 2.0)  # ratios outside this band (and not a known factor) are an error
# Star connection checks of validate().
_STAR_MEAN_LIMIT = 0.10  # |mean(i_a+i_b+i_c)| / RMS phase current
_STAR_AC_LIMIT = 0.25  # RMS of the noise-free part of the sum / that of the phase currents

_FIELDS_1D = ("t", "theta_ref", "theta_m", "omega_m")


class TraceError(ValueError):
    """A trace, or a trace file, that cannot be used as it is.

    The message says what is wrong, where (column, first bad row and its time) and how to
    fix it.
    """


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


def _dumps(meta: dict) -> str:
    # ensure_ascii keeps the CSV metadata on one ASCII line whatever the strings hold.
    return json.dumps(meta, ensure_ascii=True, allow_nan=True)


def _loads(text: str | bytes, source: str) -> dict:
    try:
        meta = json.loads(text)
    except json.JSONDecodeError as exc:
        raise TraceError(
            f"{source}: the emaphm metadata is not valid JSON ({exc}); repair or delete "
            "the metadata (the data columns can still be read without it)"
        ) from None
    if not isinstance(meta, dict):
        raise TraceError(
            f"{source}: the emaphm metadata is a JSON {type(meta).__name__}, expected a "
            "JSON object; repair or delete the metadata"
        )
    return meta


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
        """The signals as 1-D read-only arrays: :data:`COLUMNS` order, then ``torque`` if set."""
        cols = {name: getattr(self, name) for name in COLUMNS}
        if self.torque is not None:
            cols["torque"] = self.torque
        return cols

    @classmethod
    def from_columns(cls, columns: Mapping[str, Any], meta: Mapping | None = None) -> Trace:
        """Build a trace from a mapping of column name -> 1-D array.

        Needs every name of :data:`COLUMNS`; ``torque`` is used when present; other keys
        are ignored.
        """
        _require_columns(columns.keys())
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
        )

    def with_meta(self, **updates: Any) -> Trace:
        """A copy with ``meta`` updated by ``updates`` (arrays are shared, not copied)."""
        return dataclasses.replace(self, meta={**self.meta, **updates})

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Trace):
            return NotImplemented
        if (self.torque is None) != (other.torque is None):
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
        return (
            f"Trace(n={self.n}, dt={self.dt:.6g} s, duration={self.duration:.6g} s, "
            f"torque={torque}, meta keys={sorted(self.meta)})"
        )


def _bitwise_equal(a: np.ndarray, b: np.ndarray) -> bool:
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if not np.array_equal(nan_a, nan_b):
        return False
    keep = ~nan_a
    return bool(np.array_equal(a[keep].view(np.uint64), b[keep].view(np.uint64)))


def _require_columns(found: Any, source: str = "") -> None:
    found = list(found)
    missing = [c for c in COLUMNS if c not in found]
    if missing:
        prefix = f"{source}: " if source else ""
        raise TraceError(
            f"{prefix}missing column(s) {missing}; found {found}. A trace needs the "
            f"columns {_expected_columns()}; rename the columns of the export to these "
            "names (units as given in brackets)"
        )


# --------------------------------------------------------------------------------------
# Units
# --------------------------------------------------------------------------------------

_SI_SPELLINGS: dict[str, set[str]] = {
    "s": {"s", "sec", "second", "seconds"},
    "rad": {"rad", "radian", "radians"},
    "rad/s": {"rad/s", "rad/sec", "rad s^-1", "rad*s^-1", "rad s-1", "rad.s-1", "rad s⁻¹"},
    "A": {"a", "amp", "amps", "ampere", "amperes"},
    "N m": {"n m", "nm", "n*m", "n.m", "n·m", "n-m", "newton metre", "newton meter"},
}
# unit (lower case) -> (SI unit, factor to SI, how to write the factor)
_NON_SI: dict[str, tuple[str, float, str]] = {
    "ms": ("s", 1e-3, "0.001 (divide by 1000)"),
    "us": ("s", 1e-6, "1e-6"),
    "µs": ("s", 1e-6, "1e-6"),
    "μs": ("s", 1e-6, "1e-6"),
    "min": ("s", 60.0, "60"),
    "h": ("s", 3600.0, "3600"),
    "deg": ("rad", math.pi / 180, "pi/180"),
    "degree": ("rad", math.pi / 180, "pi/180"),
    "degrees": ("rad", math.pi / 180, "pi/180"),
    "°": ("rad", math.pi / 180, "pi/180"),
    "rev": ("rad", 2 * math.pi, "2*pi"),
    "revs": ("rad", 2 * math.pi, "2*pi"),
    "revolutions": ("rad", 2 * math.pi, "2*pi"),
    "turn": ("rad", 2 * math.pi, "2*pi"),
    "turns": ("rad", 2 * math.pi, "2*pi"),
    "rpm": ("rad/s", 2 * math.pi / 60, "2*pi/60"),
    "r/min": ("rad/s", 2 * math.pi / 60, "2*pi/60"),
    "rev/min": ("rad/s", 2 * math.pi / 60, "2*pi/60"),
    "1/min": ("rad/s", 2 * math.pi / 60, "2*pi/60"),
    "rps": ("rad/s", 2 * math.pi, "2*pi"),
    "rev/s": ("rad/s", 2 * math.pi, "2*pi"),
    "deg/s": ("rad/s", math.pi / 180, "pi/180"),
    "°/s": ("rad/s", math.pi / 180, "pi/180"),
    "degree/s": ("rad/s", math.pi / 180, "pi/180"),
    "degrees/s": ("rad/s", math.pi / 180, "pi/180"),
    "ma": ("A", 1e-3, "0.001 (divide by 1000)"),
    "ka": ("A", 1e3, "1000"),
    "mn m": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "mnm": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "mn*m": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "mn.m": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "mn·m": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "n mm": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "n*mm": ("N m", 1e-3, "0.001 (divide by 1000)"),
    "nmm": ("N m", 1e-3, "0.001 (divide by 1000)"),
}


def _unbracket(unit: str) -> str:
    unit = unit.strip()
    if len(unit) >= 2 and unit[0] + unit[-1] in ("[]", "()"):
        unit = unit[1:-1].strip()
    return unit


def _normalise_unit(unit: str) -> str:
    return " ".join(_unbracket(unit).split()).lower()


def _check_unit(column: str, unit: Any, source: str) -> None:
    """Raise TraceError unless ``unit`` is empty or an SI spelling of ``UNITS[column]``."""
    expected = UNITS[column]
    if not isinstance(unit, str):
        raise TraceError(
            f"{source}: the unit of column '{column}' is {unit!r}, expected the string "
            f"'{expected}'"
        )
    u = _normalise_unit(unit)
    if u in ("", "-"):
        return
    if u in _SI_SPELLINGS[expected]:
        return
    if u in _NON_SI:
        si, _factor, how = _NON_SI[u]
        if si == expected:
            raise TraceError(
                f"{source}: column '{column}' is in '{_unbracket(unit)}', emaphm needs SI "
                f"units ({expected}); multiply the column by {how} to convert it to "
                f"{expected} and change its unit to '{expected}'"
            )
    for si, spellings in _SI_SPELLINGS.items():
        if u in spellings or (u in _NON_SI and _NON_SI[u][0] == si):
            raise TraceError(
                f"{source}: column '{column}' has the unit '{_unbracket(unit)}' (a unit of "
                f"{si}), but '{column}' must be in {expected}; check the column "
                f"assignment ({_expected_columns()})"
            )
    raise TraceError(
        f"{source}: column '{column}' has the unrecognised unit '{_unbracket(unit)}'; "
        f"convert the column to {expected} and write its unit as '{expected}'"
    )


def _check_declared_units(units: Any, source: str) -> None:
    if units is None:
        return
    if not isinstance(units, Mapping):
        raise TraceError(
            f"{source}: meta['units'] is a {type(units).__name__}, expected a mapping "
            "of column name to unit string, e.g. {'t': 's', 'omega_m': 'rad/s'}"
        )
    for name, unit in units.items():
        if name == "i_abc":
            _check_unit("i_a", unit, source)
        elif name in UNITS:
            _check_unit(name, unit, source)


# --------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------


def _where(trace: Trace, index: int) -> str:
    t = trace.t[index] if 0 <= index < trace.n else math.nan
    return f"row {index} (t = {t:.9g} s)" if math.isfinite(t) else f"row {index}"


_SPEED_FACTORS: tuple[tuple[float, str], ...] = (
    (60 / (2 * math.pi), "omega_m looks like rpm: multiply omega_m by 2*pi/60 to get rad/s"),
    (180 / math.pi, "omega_m looks like deg/s: multiply omega_m by pi/180 to get rad/s"),
    (math.pi / 180, "theta_m looks like degrees: multiply theta_m and theta_ref by pi/180 "
     "to get rad"),
    (1 / 6, "theta_m looks like degrees and omega_m like rpm: multiply theta_m and "
     "theta_ref by pi/180 and omega_m by 2*pi/60"),
    (2 * math.pi, "theta_m looks like revolutions: multiply theta_m and theta_ref by 2*pi "
     "to get rad"),
    (60.0, "theta_m looks like revolutions and omega_m like rpm: multiply theta_m and "
     "theta_ref by 2*pi and omega_m by 2*pi/60"),
    (360.0, "theta_m looks like revolutions and omega_m like deg/s: multiply theta_m and "
     "theta_ref by 2*pi and omega_m by pi/180"),
)


def _check_speed_units(trace: Trace) -> None:
    theta, omega = trace.theta_m, trace.omega_m
    if np.ptp(theta) == 0.0:
        return
    d_theta = np.gradient(theta, trace.t)
    sdd = float(np.dot(d_theta, d_theta))
    sww = float(np.dot(omega, omega))
    if sdd == 0.0 or sww == 0.0 or not (math.isfinite(sdd) and math.isfinite(sww)):
        return
    swd = float(np.dot(omega, d_theta))
    cosine = swd / math.sqrt(sdd * sww)
    if abs(cosine) < _MIN_SPEED_CORRELATION:
        return  # too noisy (or too little motion) to judge the units
    ratio = swd / sdd  # least squares: omega_m ~ ratio * d(theta_m)/dt
    lead = (
        f"omega_m does not match the time derivative of theta_m: the least-squares "
        f"ratio omega_m / (d theta_m/dt) is {ratio:.4g}, expected 1"
    )
    if ratio < 0:
        if abs(math.log(-ratio)) < math.log1p(_RATIO_TOLERANCE):
            raise TraceError(
                f"{lead}; omega_m has the opposite sign to d theta_m/dt: negate omega_m "
                "(or theta_m and theta_ref) so that both use the same positive direction"
            )
        raise TraceError(
            f"{lead}; the sign is opposite too. Check that both are motor-side signals "
            "in rad and rad/s with the same positive direction"
        )
    if abs(math.log(ratio)) < math.log1p(_RATIO_TOLERANCE):
        return
    near = sorted(
        (abs(math.log(ratio / factor)), factor, text) for factor, text in _SPEED_FACTORS
    )
    hits = [
        f"{text} (expected ratio {factor:.4g})"
        for distance, factor, text in near
        if distance < math.log1p(_RATIO_TOLERANCE)
    ]
    if hits:
        raise TraceError(f"{lead}, a units error; " + "; or ".join(hits))
    if not _RATIO_BAND[0] <= ratio <= _RATIO_BAND[1]:
        raise TraceError(
            f"{lead}. Check that theta_m and omega_m are both motor-side (not load-side "
            "through the gear ratio), in rad and rad/s, and come from the same run"
        )


def _lag1_power(x: np.ndarray) -> float:
    """mean(x[k] x[k+1]): the power of the smooth part of ``x``; white noise averages out."""
    return float(np.mean(x[:-1] * x[1:]))


def _check_star(trace: Trace) -> None:
    i_abc = trace.i_abc
    i_rms = float(np.sqrt(np.mean(i_abc * i_abc)))
    if i_rms == 0.0:
        return
    s = i_abc.sum(axis=1)
    worst = int(np.argmax(np.abs(s)))
    hint = (
        "Check for a swapped or missing phase, a wrong sign on one phase or a current "
        "sensor offset; if only two phases were measured, set i_c = -(i_a + i_b)"
    )
    flat = [p for k, p in enumerate(("i_a", "i_b", "i_c")) if np.ptp(i_abc[:, k]) == 0.0]
    if flat:
        hint = f"{', '.join(flat)} is constant throughout (a missing phase?). " + hint
    mean = float(np.mean(s))
    where = (
        f"largest |i_a + i_b + i_c| = {abs(s[worst]):.4g} A at {_where(trace, worst)}"
    )
    if abs(mean) > _STAR_MEAN_LIMIT * i_rms:
        raise TraceError(
            f"the phase currents do not sum to zero as a star connection requires: "
            f"mean(i_a + i_b + i_c) = {mean:.4g} A is {abs(mean) / i_rms:.0%} of the RMS "
            f"phase current {i_rms:.4g} A (limit {_STAR_MEAN_LIMIT:.0%}); {where}. {hint}"
        )
    # Compare the smooth (noise-free) parts only, so that white measurement noise, which
    # does not cancel in the sum, is not mistaken for a wiring error; demand that the
    # excess stands well above the estimator's own scatter (5 sigma for white noise).
    s_ac = s - mean
    p_phase = float(np.mean([_lag1_power(i_abc[:, k]) for k in range(3)]))
    p_sum = _lag1_power(s_ac)
    scatter = float(np.mean(s_ac * s_ac)) / math.sqrt(trace.n - 1)
    if p_phase <= 0.0 or p_sum <= _STAR_AC_LIMIT**2 * p_phase + 5.0 * scatter:
        return
    ratio = math.sqrt(p_sum / p_phase)
    if ratio > _STAR_AC_LIMIT:
        raise TraceError(
            f"the phase currents do not sum to zero as a star connection requires: the "
            f"RMS of i_a + i_b + i_c is {ratio:.0%} of the RMS phase current (limit "
            f"{_STAR_AC_LIMIT:.0%}); {where}. {hint}"
        )


def validate(
    trace: Trace, *, min_rotation: float = 2 * np.pi, rtol_dt: float = 1e-3
) -> Trace:
    """Check that ``trace`` can be diagnosed; return it unchanged, or raise :class:`TraceError`.

    Checks, in order: declared units (``meta["units"]``) are SI; at least
    :data:`MIN_SAMPLES` samples; all values finite; ``t`` strictly increasing, in
    seconds (step <= 0.01 s and duration <= 1000 s) and uniform (relative spread of the
    steps <= ``rtol_dt``); currents in A (|i| <= 1000 A); ``omega_m`` consistent with
    the derivative of ``theta_m`` (catches rpm, deg/s, degrees, revolutions and sign
    errors when there is clear motion); rotation range ``max(theta_m) - min(theta_m) >=
    min_rotation`` (rad, 0 disables); phase currents summing to about zero (star
    connection).

    ==============  =====  ==========================================================
    argument        unit   meaning
    ==============  =====  ==========================================================
    min_rotation    rad    least motor rotation range; one revolution by default
    rtol_dt         1      largest (max step - min step) / mean step
    ==============  =====  ==========================================================
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"validate() needs a Trace, got {type(trace).__name__}")
    if not (math.isfinite(min_rotation) and min_rotation >= 0):
        raise ValueError(f"min_rotation must be finite and >= 0 rad, got {min_rotation!r}")
    if not (math.isfinite(rtol_dt) and rtol_dt > 0):
        raise ValueError(f"rtol_dt must be finite and > 0, got {rtol_dt!r}")

    _check_declared_units(trace.meta.get("units"), "meta['units']")

    n = trace.n
    if n < MIN_SAMPLES:
        raise TraceError(
            f"trace too short: {n} samples, at least {MIN_SAMPLES} are needed; record a "
            "longer profile, e.g. the default diagnostic profile "
            "emaphm.profiles.diagnostic()"
        )

    for name, values in trace.columns().items():
        bad = ~np.isfinite(values)
        if bad.any():
            first = int(np.argmax(bad))
            kind = "NaN" if np.isnan(values[first]) else "inf"
            raise TraceError(
                f"column '{name}' holds {int(bad.sum())} non-finite value(s), the first "
                f"({kind}) at {_where(trace, first)}; remove or interpolate the bad "
                "samples (or cut the trace before them)"
            )

    t = trace.t
    steps = np.diff(t)
    bad = steps <= 0
    if bad.any():
        first = int(np.argmax(bad)) + 1
        raise TraceError(
            f"column 't' is not strictly increasing: t[{first}] = {t[first]:.9g} s <= "
            f"t[{first - 1}] = {t[first - 1]:.9g} s ({_where(trace, first)}); sort the "
            "samples by time and drop duplicated time stamps"
        )

    dt, duration = trace.dt, trace.duration
    if dt > _MAX_TIME_STEP or duration > _MAX_DURATION:
        raise TraceError(
            f"column 't' looks like milliseconds, not seconds: mean step {dt:.6g}, "
            f"duration {duration:.6g} (a trace in seconds has a step <= {_MAX_TIME_STEP} s "
            f"and lasts <= {_MAX_DURATION:g} s); divide t by 1000. If it really is in "
            "seconds, resample it finer or split it into shorter windows"
        )

    spread = float((steps.max() - steps.min()) / dt)
    if spread > rtol_dt:
        first = int(np.argmax(np.abs(steps - dt) > 0.5 * rtol_dt * dt)) + 1
        raise TraceError(
            f"column 't' is not uniform: the time steps spread by {spread:.3g} of the mean "
            f"step {dt:.6g} s (tolerance rtol_dt = {rtol_dt:g}); the first irregular step "
            f"ends at {_where(trace, first)}. Resample onto a uniform grid: "
            "emaphm.traces.resample(trace, numpy.linspace(trace.t[0], trace.t[-1], "
            "trace.n)) (read files with read_trace(path, validate=False) first)"
        )

    for k, name in enumerate(("i_a", "i_b", "i_c")):
        column = trace.i_abc[:, k]
        big = np.abs(column) > _MAX_CURRENT
        if big.any():
            first = int(np.argmax(big))
            raise TraceError(
                f"column '{name}' looks like mA, not A: |{name}| = {abs(column[first]):.6g} "
                f"> {_MAX_CURRENT:g} at {_where(trace, first)}; divide the phase currents "
                "by 1000"
            )

    _check_speed_units(trace)

    if min_rotation > 0:
        rotation = float(np.ptp(trace.theta_m))
        if rotation < min_rotation:
            raise TraceError(
                f"trace too short in rotation: max(theta_m) - min(theta_m) = "
                f"{rotation:.4g} rad is below min_rotation = {min_rotation:.4g} rad; "
                "eccentricity identification needs at least one full mechanical "
                "revolution. Record a longer profile, e.g. the default diagnostic profile "
                "emaphm.profiles.diagnostic(), or pass min_rotation=0 to skip this check"
            )

    _check_star(trace)
    return trace


# --------------------------------------------------------------------------------------
# Resampling
# --------------------------------------------------------------------------------------


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
    signals = np.column_stack(
        [trace.theta_ref, trace.theta_m, trace.omega_m, trace.i_abc]
        + ([trace.torque] if trace.torque is not None else [])
    )
    y0, y1 = signals[idx], signals[idx + 1]
    out = np.where(w == 1.0, y1, y0 + w * (y1 - y0))
    return Trace(
        t=t_new,
        theta_ref=out[:, 0],
        theta_m=out[:, 1],
        omega_m=out[:, 2],
        i_abc=out[:, 3:6],
        torque=out[:, 6] if trace.torque is not None else None,
        meta=trace.meta,
    )


# --------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise TraceError(
            f"{path}: unsupported file type '{path.suffix}'; use one of "
            f"{', '.join(SUFFIXES)} (e.g. {path.with_suffix('.parquet').name})"
        )
    return suffix


def _atomic_write(path: Path, write: Callable[[IO[bytes]], None]) -> None:
    """:func:`emaphm._files.atomic_write` (kept under this name for the trace writers)."""
    atomic_write(path, write)


def _csv_chunks(trace: Trace, rows_per_chunk: int = 8192) -> Iterator[bytes]:
    cols = trace.columns()
    yield f"{_CSV_MAGIC} {FORMAT_VERSION} {_dumps(trace.meta)}\n".encode("ascii")
    yield (",".join(cols) + "\n").encode("ascii")
    data = np.column_stack(list(cols.values())) if trace.n else np.empty((0, len(cols)))
    for start in range(0, trace.n, rows_per_chunk):
        rows = data[start:start + rows_per_chunk].tolist()
        # repr(float) is the shortest string that reads back to the same double.
        text = "".join(",".join(map(repr, row)) + "\n" for row in rows)
        yield text.encode("ascii")


def _write_csv(trace: Trace, fh: IO[bytes]) -> None:
    for chunk in _csv_chunks(trace):
        fh.write(chunk)


def _write_parquet(trace: Trace, fh: IO[bytes]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    cols = trace.columns()
    schema = pa.schema(
        [pa.field(name, pa.float64(), nullable=False) for name in cols],
        metadata={
            _PARQUET_META_KEY: _dumps(trace.meta).encode("ascii"),
            _PARQUET_VERSION_KEY: str(FORMAT_VERSION).encode("ascii"),
        },
    )
    table = pa.table({name: pa.array(v, type=pa.float64()) for name, v in cols.items()},
                     schema=schema)
    pq.write_table(table, fh)


def write_trace(trace: Trace, path: str | os.PathLike[str]) -> Path:
    """Write ``trace`` atomically to ``path`` (``.csv`` or ``.parquet``, by suffix); return it.

    The trace is written as it is (no validation), metadata included. The parent
    directory must exist. An existing file is replaced only once the new one is complete.
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"write_trace() needs a Trace, got {type(trace).__name__}")
    path = Path(path)
    suffix = _suffix(path)
    writer = _write_csv if suffix == ".csv" else _write_parquet
    _atomic_write(path, lambda fh: writer(trace, fh))
    return path


_HEADER_UNIT = re.compile(r"^(?P<name>.*?)\s*(?P<unit>\[[^\]]*\]|\([^)]*\))$")


def _split_name(cell: str) -> tuple[str, str | None]:
    cell = cell.strip().strip('"').strip("'").strip()
    m = _HEADER_UNIT.match(cell)
    if m and m.group("name"):
        return m.group("name").strip(), m.group("unit")
    return cell, None


def _is_number(text: str) -> bool:
    try:
        float(text.strip().strip('"'))
    except ValueError:
        return False
    return True


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    source = str(path)
    meta: dict = {}
    header: str | None = None
    consumed = 0
    units_row: list[str] | None = None
    with open(path, encoding="utf-8-sig", newline=None) as fh:
        for line in fh:
            consumed += 1
            s = line.strip()
            if not s:
                continue
            if s.startswith("#"):
                body = s[1:].strip()
                if body.startswith("emaphm-trace"):
                    parts = body[len("emaphm-trace"):].strip().split(maxsplit=1)
                    if not parts or not parts[0].isdigit():
                        raise TraceError(
                            f"{source}: malformed first line {s[:60]!r}; expected "
                            f"'{_CSV_MAGIC} {FORMAT_VERSION} {{json}}'"
                        )
                    if int(parts[0]) > FORMAT_VERSION:
                        raise TraceError(
                            f"{source}: written in emaphm trace format {parts[0]}, this "
                            f"version reads format {FORMAT_VERSION}; upgrade emaphm"
                        )
                    meta = _loads(parts[1], source) if len(parts) > 1 else {}
                continue
            header = s
            break
        if header is None:
            raise TraceError(
                f"{source}: no header row found; the first non-comment line must name the "
                f"columns, e.g. '{','.join(COLUMNS)}'"
            )
        counts = {d: header.count(d) for d in (",", ";", "\t")}
        delimiter = max(counts, key=counts.get) if max(counts.values()) else ","
        cells = header.split(delimiter)
        if all(_is_number(c) for c in cells):
            raise TraceError(
                f"{source}: the first row holds numbers, not column names; add a header "
                f"row '{','.join(COLUMNS)}'"
            )
        for line in fh:
            s = line.strip()
            if not s or s.startswith("#"):
                consumed += 1
                continue
            row = [c.strip().strip('"').strip() for c in s.split(delimiter)]
            if all(not c or c[0] + c[-1] in ("[]", "()") for c in row):
                units_row = row
                consumed += 1
            break

    names: list[str] = []
    units: dict[str, str] = {}
    for k, cell in enumerate(cells):
        name, unit = _split_name(cell)
        names.append(name)
        if units_row is not None and k < len(units_row) and units_row[k]:
            unit = units_row[k]
        if unit is not None and name in UNITS and _unbracket(unit):
            units[name] = _unbracket(unit)
    dupes = sorted({n for n in names if n in UNITS and names.count(n) > 1})
    if dupes:
        raise TraceError(f"{source}: column(s) {dupes} appear more than once; keep one each")
    _require_columns(names, source)

    wanted = [c for c in COLUMNS + OPTIONAL_COLUMNS if c in names]
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*input contained no data.*")
        try:
            data = np.loadtxt(
                path,
                dtype=np.float64,
                delimiter=delimiter,
                comments="#",
                skiprows=consumed,
                usecols=[names.index(c) for c in wanted],
                ndmin=2,
                encoding="utf-8",
                quotechar='"',
            )
        except ValueError as exc:
            where = ""
            m = re.search(r"at row (\d+), column (\d+)", str(exc))
            if m and 0 < int(m.group(2)) <= len(names):  # numpy: row from 0, column from 1
                where = f" in data row {m.group(1)}, column '{names[int(m.group(2)) - 1]}'"
            raise TraceError(
                f"{source}: cannot read the data as numbers{where} ({exc}); every data row "
                f"needs a number in each of the columns {wanted} (write missing values as "
                "'nan')"
            ) from None
    columns = {name: data[:, k] for k, name in enumerate(wanted)}

    if units:
        declared = meta.get("units")
        if isinstance(declared, Mapping):
            for name, unit in units.items():
                other = declared.get(name)
                if isinstance(other, str) and _normalise_unit(other) != _normalise_unit(unit):
                    raise TraceError(
                        f"{source}: column '{name}' is declared in '{other}' by the "
                        f"metadata but in '{unit}' by the header; make them agree"
                    )
            meta["units"] = {**declared, **units}
        else:
            meta["units"] = units
    return columns, meta


def _read_parquet(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    source = str(path)
    try:
        schema = pq.read_schema(path)
    except (pa.ArrowInvalid, OSError) as exc:
        if isinstance(exc, FileNotFoundError):
            raise
        raise TraceError(f"{source}: not a readable Parquet file ({exc})") from None
    raw = (schema.metadata or {})
    version = raw.get(_PARQUET_VERSION_KEY)
    if version is not None and version.isdigit() and int(version) > FORMAT_VERSION:
        raise TraceError(
            f"{source}: written in emaphm trace format {version.decode()}, this version "
            f"reads format {FORMAT_VERSION}; upgrade emaphm"
        )
    meta = _loads(raw[_PARQUET_META_KEY], source) if _PARQUET_META_KEY in raw else {}
    names = list(schema.names)
    _require_columns(names, source)
    wanted = [c for c in COLUMNS + OPTIONAL_COLUMNS if c in names]
    table = pq.read_table(path, columns=wanted)
    columns = {}
    for name in wanted:
        col = table.column(name)
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
            raise TraceError(
                f"{source}: column '{name}' has type {col.type}, expected numbers in "
                f"{UNITS[name]}; store it as float64"
            )
        # nulls become NaN, which validation reports with their row
        columns[name] = col.to_numpy(zero_copy_only=False).astype(np.float64)
    return columns, meta


def read_trace(
    path: str | os.PathLike[str],
    *,
    validate: bool = True,
    min_rotation: float = 2 * np.pi,
) -> Trace:
    """Read a trace from ``path`` (``.csv`` or ``.parquet``, by suffix).

    With ``validate=True`` (default) the trace goes through :func:`validate` (with
    ``min_rotation``, rad) and every problem is raised as :class:`TraceError` prefixed
    with the path. Units given in a CSV header (``name [unit]`` or a units row) are
    stored in ``meta["units"]`` and checked by :func:`validate`.
    """
    path = Path(path)
    suffix = _suffix(path)
    if path.is_dir():
        raise TraceError(f"{path} is a folder; give a trace file (.csv or .parquet)")
    try:
        columns, meta = _read_csv(path) if suffix == ".csv" else _read_parquet(path)
    except (TraceError, FileNotFoundError):
        raise
    except UnicodeDecodeError as exc:
        raise TraceError(f"{path}: not a UTF-8 text file (undecodable byte at position "
                         f"{exc.start}); export the CSV as UTF-8 text") from None
    except RecursionError:
        raise TraceError(f"{path}: its metadata is nested too deeply to read; the file is "
                         "malformed, export it again") from None
    except (ValueError, TypeError, KeyError, IndexError, OverflowError, OSError) as exc:
        # a malformed file reaches the parsers' own errors (CSV, JSON, Parquet: pyarrow
        # reports a corrupt file as an OSError)
        raise TraceError(f"{path}: cannot be read as a {suffix[1:]} trace ({type(exc).__name__}: "
                         f"{str(exc)[:200]}); check that it is an emaphm or bench export") from None
    try:
        trace = Trace.from_columns(columns, meta=meta)
    except TraceError as exc:
        raise TraceError(f"{path}: {exc}") from None
    if validate:
        try:
            _validate(trace, min_rotation=min_rotation)
        except TraceError as exc:
            raise TraceError(f"{path}: {exc}") from None
    return trace


_validate = validate
