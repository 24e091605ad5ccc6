"""Trace files: :func:`write_trace` and :func:`read_trace` choose the format by suffix
(:mod:`~emaphm.traces.csv_format`, :mod:`~emaphm.traces.parquet_format`). Writes are
atomic: the file is written to a temporary sibling and moved over the target, so a
failure never leaves a half-written file."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import IO

import numpy as np

from .._files import atomic_write, regular_file
from .container import Trace, TraceError
from .csv_format import _read_csv, _write_csv
from .parquet_format import _read_parquet, _write_parquet
from .timebase import from_epoch, warn_if_shorter_than_profile
from .validation import validate as _validate

__all__ = ["SUFFIXES", "write_trace", "read_trace", "first_nonfinite"]

#: File suffixes understood by :func:`write_trace` and :func:`read_trace`.
SUFFIXES: tuple[str, ...] = (".csv", ".parquet")


def _suffix(path: Path, reading: bool = False) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        from .importers.registry import SUFFIXES as EXPORTS
        from .validation import _import_command

        raise TraceError(
            f"{path}: unsupported file type '{path.suffix}'; use one of "
            f"{', '.join(SUFFIXES)} (e.g. {path.with_suffix('.parquet').name})"
            + (f", or import the export as it is: {_import_command(path, '--inspect')} "
               "prints a channel map to edit" if reading and suffix in EXPORTS else "")
        )
    return suffix


def _atomic_write(path: Path, write: Callable[[IO[bytes]], None]) -> None:
    """:func:`emaphm._files.atomic_write` (kept under this name for the trace writers)."""
    atomic_write(path, write)


def first_nonfinite(trace: Trace) -> tuple[str, int, int] | None:
    """``(column, first row, count)`` of the first column of ``trace`` holding NaN or an
    infinity, or None when every sample is finite."""
    columns = {"t": trace.t, "theta_ref": trace.theta_ref, "theta_m": trace.theta_m,
               "omega_m": trace.omega_m, "i_a": trace.i_abc[:, 0], "i_b": trace.i_abc[:, 1],
               "i_c": trace.i_abc[:, 2]}
    if trace.torque is not None:
        columns["torque"] = trace.torque
    for name, x in columns.items():
        bad = ~np.isfinite(x)
        if bad.any():
            return name, int(np.argmax(bad)), int(bad.sum())
    return None


def write_trace(trace: Trace, path: str | os.PathLike[str], *, finite: bool = False) -> Path:
    """Write ``trace`` atomically to ``path`` (``.csv`` or ``.parquet``, by suffix); return it.

    The trace is written as it is (no validation), metadata included; with ``finite``,
    a trace holding NaN or an infinity is refused (a TraceError, nothing written), as the
    command line does for every trace it writes. The parent directory must exist. An
    existing file is replaced only once the new one is complete.
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"write_trace() needs a Trace, got {type(trace).__name__}")
    path = Path(path)
    suffix = _suffix(path)
    bad = first_nonfinite(trace) if finite else None
    if bad is not None:
        name, row, count = bad
        raise TraceError(f"{path}: not written: column {name} holds {count:,} samples that are NaN "
                         f"or infinite, the first at row {row:,} of {trace.n:,}; a trace holds "
                         "finite numbers")
    writer = _write_csv if suffix == ".csv" else _write_parquet
    _atomic_write(path, lambda fh: writer(trace, fh))
    return path


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

    Only a regular file is read (a folder, a FIFO, a device or a link loop is refused with
    a :class:`TraceError`; a missing file is a :class:`FileNotFoundError`). Files above
    :data:`~emaphm.traces.limits.MAX_FILE_BYTES` or with more than
    :data:`~emaphm.traces.limits.MAX_SAMPLES` rows are refused before they are read
    whole. With ``validate``, clock times (a Unix time in ``t``) are shifted to start at 0, and a trace
    shorter than the test profile its metadata names is read; both with a
    :class:`~emaphm.traces.container.TraceWarning`.
    """
    path = Path(path)
    suffix = _suffix(path, reading=True)
    # a FIFO would block, a link to a device never end: a regular file or a TraceError
    regular_file(path, "trace file", give="a trace file (.csv or .parquet)", error=TraceError)
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
    t = columns.get("t")
    if validate and t is not None:
        columns["t"], t_start = from_epoch(np.asarray(t, dtype=np.float64), str(path))
        if t_start is not None:
            meta = {**meta, "t_start": t_start}
    try:
        trace = Trace.from_columns(columns, meta=meta)
    except TraceError as exc:
        raise TraceError(f"{path}: {exc}") from None
    warn_if_shorter_than_profile(trace, str(path))
    if validate:
        try:
            _validate(trace, min_rotation=min_rotation, source=path)
        except TraceError as exc:
            raise TraceError(f"{path}: {exc}") from None
    return trace
