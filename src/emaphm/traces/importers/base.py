"""What every format reader of :mod:`emaphm.traces.importers` gives: a :class:`SourceInfo`
(the channels found, with their units, lengths and rates) and blocks of rows of the
channels asked for (:class:`Block`). A reader is a class with ``open(path, options)``
that returns a :class:`Source`; the registry (:mod:`.registry`) picks it by suffix."""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Protocol

import numpy as np

from ..container import TraceError

__all__ = ["ChannelInfo", "SourceInfo", "Block", "Source", "MissingReaderError", "need",
           "BLOCK_ROWS", "cause"]

#: Rows per block a reader yields where it chooses (binary formats).
BLOCK_ROWS = 1 << 20


class MissingReaderError(TraceError):
    """The library that reads a format is not installed (the ``bench`` extra)."""


def need(module: str, what: str) -> ModuleType:
    """Import ``module`` (the reader of ``what``), or a :class:`MissingReaderError` saying
    which extra to install."""
    try:
        return importlib.import_module(module)
    except ImportError:
        package = module.split(".")[0]
        raise MissingReaderError(
            f"reading {what} needs the Python package {package!r}, which is not installed: "
            "pip install 'emaphm[bench]'") from None


@dataclass(frozen=True)
class ChannelInfo:
    """A channel of a file: its ``name`` (and ``group`` where the format has groups: a TDMS
    group, an MDF channel group, a MATLAB struct), the unit the file declares (or None),
    its number of samples (None where unknown before reading, e.g. CSV), and its sample
    ``rate`` [Hz] and ``start`` [s] where the file gives the channel a time base. ``text``
    is a value of a column that holds text, not numbers (a CSV status column): listed,
    never read."""

    name: str
    group: str | None = None
    unit: str | None = None
    samples: int | None = None
    rate: float | None = None
    start: float | None = None
    text: str | None = None

    @property
    def label(self) -> str:
        return f"{self.group}/{self.name}" if self.group else self.name


@dataclass(frozen=True)
class SourceInfo:
    """What :meth:`Source.info` found in a file: its ``format`` (``csv``, ``mat``...), its
    channels, and ``notes`` on how it is written (delimiter, decimal comma, a preamble);
    ``skipped``, what the file holds that is not read as channels (a MATLAB matrix),
    ``hint``, advice a refusal adds (a map's delimiter that the file seems not to use), and
    ``damage``, what is wrong with a file whose whole part is listed (a truncated one):
    ``--inspect`` warns of it, an import refuses the file."""

    path: Path
    format: str
    channels: tuple[ChannelInfo, ...]
    notes: tuple[str, ...] = ()
    #: the file's own time base (an MDF master channel) is given with each block
    own_time: bool = False
    skipped: tuple[str, ...] = ()
    hint: str = ""
    damage: str = ""

    def find(self, name: str, group: str | None, where: str) -> ChannelInfo:
        """The channel called ``name`` (in ``group``, where given), or a TraceError naming
        the channels that exist."""
        # a nested MATLAB group is Run.Messung; a map may write its HDF5 path, Run/Messung
        alias = None if group is None else group.replace("/", ".")
        hits = [c for c in self.channels
                if c.name == name and (group is None or c.group in (group, alias))]
        if not hits and "/" in name:
            hits = self._by_label(name, group)
        if len(hits) == 1:
            return hits[0]
        if len(hits) > 1:
            groups = sorted({str(c.group) for c in hits})
            if len(groups) == 1:                # twice in one table: no group tells them apart
                at = [k + 1 for k, c in enumerate(self.channels) if c in hits]
                what = ("column", "the header") if self.format == "csv" else \
                    ("channel", f"group {hits[0].group!r}" if hits[0].group else "the file")
                raise TraceError(f"{where}: {what[0]} {name!r} appears {len(hits)} times in "
                                 f"{what[1]} of {self.path.name} ({what[0]}s "
                                 f"{and_list(map(str, at))}); rename one in the file")
            raise TraceError(f"{where}: channel {name!r} is in several groups ({', '.join(groups)}); "
                             "say which with group = \"...\"")
        names = [c.label for c in self.channels]
        shown = ", ".join(repr(n) for n in names[:40]) + (f" and {len(names) - 40} more"
                                                          if len(names) > 40 else "")
        folded = [c.label for c in self.channels if c.name.lower() == name.lower()]
        hint = f" (did you mean {folded[0]!r}?)" if folded else ""
        in_group = f" in group {group!r}" if group is not None else ""
        has = f"the file has {shown}" if names else "the file has no channel it can read"
        skipped = "".join(f"; {s}" for s in self.skipped + ((self.hint,) if self.hint else ()))
        raise TraceError(f"{where}: no channel {name!r}{in_group} in {self.path.name}{hint}; "
                         f"{has}{skipped} (`emaphm import {self.path.name} --inspect` "
                         "lists them)")

    def _by_label(self, label: str, group: str | None) -> list[ChannelInfo]:
        """The channels a ``"GROUP/CHANNEL"`` name means (as ``--inspect`` lists them; a
        MATLAB struct in a struct as ``Run.Messung/x`` or ``Run/Messung/x``), in ``group``
        where one is given."""
        head, _, leaf = label.rpartition("/")
        folded = head.replace("/", ".")
        return [c for c in self.channels if c.name == leaf and c.group is not None
                and c.group in (head, folded)
                and (group is None or c.group in (group, group.replace("/", ".")))]


@dataclass(frozen=True)
class Block:
    """Rows ``start`` to ``start + n`` of the channels asked for, one float64 array each;
    ``t`` [s] where the file gives the time base itself (else None)."""

    start: int
    columns: tuple[np.ndarray, ...]
    t: np.ndarray | None = None

    @property
    def n(self) -> int:
        return int(self.columns[0].shape[0]) if self.columns else 0


class Source(Protocol):
    """An open file of one format."""

    info: SourceInfo

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        """The rows ``first`` to ``stop`` (None: to the end; a reader that cannot seek may
        start earlier, the blocks say where) of ``channels``, in order."""
        ...

    def close(self) -> None:
        ...


def cause(exc: BaseException, limit: int = 200) -> str:
    """What a library's exception says, for a refusal: its class and message on one line of
    printable characters (a damaged file's bytes can be in it), cut at ``limit``."""
    text = " ".join(str(exc).split())
    text = "".join(ch if ch.isprintable() else "?" for ch in text)
    return f"{type(exc).__name__}: {text[:limit]}"


def and_list(items) -> str:
    """``"3 and 5"``, ``"1, 2 and 4"``."""
    items = list(items)
    return ", ".join(items[:-1]) + " and " + items[-1] if len(items) > 1 else "".join(items)


def as_float(x, where: str) -> np.ndarray:
    """A channel's samples as a 1-D float64 array (a TraceError for text or nested data)."""
    arr = np.asarray(x)
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.reshape(-1)
    if arr.ndim != 1:
        raise TraceError(f"{where}: has shape {arr.shape}, expected one row or column of samples")
    if arr.dtype.kind not in "biuf":
        raise TraceError(f"{where}: holds {arr.dtype} values, not numbers")
    return arr.astype(np.float64, copy=False)


def read_path(path: str | Path) -> Path:
    """``path`` as a Path that is a regular file after its links (a TraceError for a
    folder, a FIFO, a device or a link loop; a FileNotFoundError when nothing is there)."""
    from ..._files import regular_file

    return regular_file(path, "source", give="the exported file", error=TraceError)
