"""NI TDMS exports (read by ``npTDMS``, from the ``bench`` extra): channels in groups, each
with its unit (``unit_string``) and, for waveforms, its time step (``wf_increment``) and
start (``wf_start_offset``); read in slices."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from ..container import TraceError
from .base import BLOCK_ROWS, Block, ChannelInfo, SourceInfo, need, read_path
from .channel_map import SourceOptions

__all__ = ["TdmsSource"]




class TdmsSource:
    """A TDMS file, opened for reading in slices."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        nptdms = need("nptdms", "NI TDMS files")
        self.path = read_path(path)
        try:
            self.file = nptdms.TdmsFile.open(self.path)
            groups = self.file.groups()
        except (ValueError, KeyError, OSError, EOFError, TypeError) as exc:
            raise TraceError(f"{self.path}: not a readable TDMS file ({str(exc)[:200]})") from None
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
                               notes=(f"{len(groups)} group(s)",))

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
