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

__all__ = ["SUFFIXES", "write_trace", "read_trace"]

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
