"""The readers by file suffix (or by ``[source] format`` in the map): one module per
format, imported when a file of that format is opened, so that the heavy libraries of the
``bench`` extra are imported only by who reads their format. The binary formats
(:data:`SANDBOXED`) are read in the sandbox (:mod:`.sandbox`), a child process whose
crash on a damaged file is a refusal, not the end of the command; CSV is read here."""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Iterator
from pathlib import Path

from ..container import TraceError
from .channel_map import SourceOptions

__all__ = ["FORMATS", "SUFFIXES", "SANDBOXED", "format_of", "open_source", "open_here"]

#: format -> (module of this package, reader class, suffixes, what it reads)
FORMATS: dict[str, tuple[str, str, tuple[str, ...], str]] = {
    "csv": ("csv", "CsvSource", (".csv", ".txt", ".tsv", ".dat"), "CSV and text exports"),
    "parquet": ("parquet", "ParquetSource", (".parquet", ".pq"), "Parquet tables"),
    "mat": ("matlab", "MatSource", (".mat",), "MATLAB files, version 5 and 7.3"),
    "tdms": ("tdms", "TdmsSource", (".tdms",), "NI TDMS files"),
    "mf4": ("mdf", "MdfSource", (".mf4", ".mdf"), "ASAM MDF 4 files"),
}
SUFFIXES: tuple[str, ...] = tuple(s for *_, suffixes, _ in FORMATS.values() for s in suffixes)
#: Formats read by a library in C (or Cython) that a damaged file can crash, read in the
#: sandbox, with what a refusal calls such a file. Their readers also run here through :func:`open_here` (in the sandbox itself).
SANDBOXED: dict[str, str] = {"parquet": "a Parquet file", "mat": "a MATLAB file",
                             "tdms": "a TDMS file", "mf4": "an MDF file"}


def format_of(path: Path, options: SourceOptions = SourceOptions()) -> str:
    """The format to read ``path`` as: ``options.format``, else by its suffix."""
    if options.format:
        return options.format
    suffix = path.suffix.lower()
    for name, (_, _, suffixes, _) in FORMATS.items():
        if suffix in suffixes:
            return name
    raise TraceError(f"{path}: cannot tell the format of a '{path.suffix}' file; emaphm import "
                     f"reads {', '.join(SUFFIXES)} (or say it in the map: [source] format = "
                     f"one of {', '.join(FORMATS)})")


@contextlib.contextmanager
def open_source(path: str | Path, options: SourceOptions = SourceOptions()) -> Iterator:
    """The open :class:`~emaphm.traces.importers.base.Source` of ``path``, closed on exit;
    a binary format is read in the sandbox (:class:`~.sandbox.SandboxedSource`)."""
    path = Path(path)
    fmt = format_of(path, options)
    if fmt not in SANDBOXED:
        with open_here(path, options) as source:
            yield source
        return
    from .sandbox import SandboxedSource

    module, cls, _, _ = FORMATS[fmt]
    source = SandboxedSource(path, f"{__package__}.{module}", cls, SANDBOXED[fmt], options)
    try:
        yield source
    finally:
        source.close()


@contextlib.contextmanager
def open_here(path: str | Path, options: SourceOptions = SourceOptions()) -> Iterator:
    """``path``'s reader in this process (what the sandbox runs), closed on exit."""
    path = Path(path)
    module, cls, _, _ = FORMATS[format_of(path, options)]
    reader = getattr(importlib.import_module(f".{module}", __package__), cls)
    source = reader(path, options)
    try:
        yield source
    finally:
        source.close()
