"""NI TDMS exports (read by ``npTDMS``, from the ``bench`` extra): channels in groups, each
with its unit (``unit_string``) and, for waveforms, its time step (``wf_increment``) and
start (``wf_start_offset``); read in slices. The chain of segments is walked first
(:func:`segments`): a lead-in that is not one is refused, a file cut inside a segment is
said to be truncated (npTDMS would read what is left, shorter, with a log line)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import struct

import numpy as np

from ..container import TraceError
from .base import BLOCK_ROWS, Block, ChannelInfo, SourceInfo, cause, need, read_path
from .channel_map import SourceOptions

__all__ = ["TdmsSource", "segments"]

_LEAD_IN = 28
_UNFINISHED = 0xFFFF_FFFF_FFFF_FFFF


def segments(path: Path) -> tuple[int, str]:
    """The number of segments of the TDMS file ``path`` and what is wrong with its end
    ("" when every segment is whole); a TraceError for a lead-in that does not add up."""
    with open(path, "rb") as fh:
        size = fh.seek(0, 2)
        pos = k = 0
        while pos < size:
            k += 1
            fh.seek(pos)
            lead = fh.read(_LEAD_IN)
            where = f"{path}: not a readable TDMS file: segment {k} (at byte {pos:,})"
            if lead[:4] not in (b"TDSm", b"TDSh"):
                raise TraceError(f"{where} does not start with 'TDSm' but {lead[:4]!r}; the file "
                                 "is damaged or is not a TDMS file: export it again")
            if len(lead) < _LEAD_IN:
                return k, (f"the file is truncated: it ends at byte {size:,}, inside the lead-in of "
                           f"segment {k} (a copy cut short, or a logger stopped mid-write); copy "
                           "or export it again")
            order = ">" if struct.unpack("<I", lead[4:8])[0] & (1 << 6) else "<"
            version, following, raw = struct.unpack(order + "IQQ", lead[8:])
            if version not in (4712, 4713) or (following != _UNFINISHED and raw > following):
                raise TraceError(f"{where}: its lead-in does not add up (version {version}, raw "
                                 f"data at {raw:,} of {following:,} bytes); the file is damaged: "
                                 "export it again")
            if following == _UNFINISHED:
                return k, (f"segment {k} (at byte {pos:,}) was never finished by its writer (a "
                           "logger stopped mid-write): its length is unknown; export it again")
            if pos + _LEAD_IN + following > size:
                return k, (f"the file is truncated (or a length in it is damaged): segment "
                           f"{k} (at byte {pos:,}) needs {following:,} bytes after its lead-in, "
                           f"and the file ends {size - pos - _LEAD_IN:,} bytes in (a copy cut "
                           "short, or a logger stopped mid-write?); copy or export it again")
            pos += _LEAD_IN + following
        return k, ""


def _cause(exc: BaseException) -> str:
    """npTDMS's exception as a cause: it looks a value's data type code up in its table, so
    a damaged code is a bare ``KeyError: 248``."""
    if isinstance(exc, KeyError) and exc.args and isinstance(exc.args[0], int):
        return f"a value of data type code {exc.args[0]}, which TDMS does not define"
    return cause(exc)


class TdmsSource:
    """A TDMS file, opened for reading in slices."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        nptdms = need("nptdms", "NI TDMS files")
        self.path = read_path(path)
        count, damage = segments(self.path)
        try:
            self.file = nptdms.TdmsFile.open(self.path)
            groups = self.file.groups()
        except (ValueError, KeyError, OSError, EOFError, TypeError) as exc:
            raise TraceError(f"{self.path}: not a readable TDMS file ({_cause(exc)}); the file is "
                             "damaged: export it again") from None
        chans = []
        self.handles = {}
        for g in groups:
            for ch in g.channels():
                if ch.dtype is None or np.dtype(ch.dtype).kind not in "biuf":
                    continue
                props = ch.properties
                inc = props.get("wf_increment")
                rate = 1.0 / float(inc) if inc else None
                start = float(props.get("wf_start_offset", 0.0)) if inc else None
                unit = props.get("unit_string") or None
                info = ChannelInfo(name=ch.name, group=g.name, unit=unit, samples=len(ch),
                                   rate=rate, start=start)
                chans.append(info)
                self.handles[(g.name, ch.name)] = ch
        self.info = SourceInfo(path=self.path, format="tdms", channels=tuple(chans),
                               notes=(f"{len(groups)} group(s), {count} segment(s)",),
                               damage=damage)

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        handles = [self.handles[(c.group, c.name)] for c in channels]
        n = min(c.samples or 0 for c in channels)
        stop = n if stop is None else min(stop, n)
        for a in range(first, stop, BLOCK_ROWS):
            b = min(a + BLOCK_ROWS, stop)
            yield Block(start=a, columns=tuple(np.asarray(h.read_data(a, b - a), dtype=np.float64)
                                               for h in handles))

    def close(self) -> None:
        self.file.close()
