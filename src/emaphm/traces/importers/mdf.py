"""ASAM MDF 4 exports of data loggers (read by ``asammdf``, from the ``bench`` extra).
Each channel group has its own master time base; the channels asked for are read on the
master of the first one's group (the assembler asks for ``i_a`` first) and the others are
resampled onto it by linear interpolation. Read in record slices, once the file's linked
lists are walked (:mod:`.mdf_links`: a link back into its own chain would send asammdf
round forever)."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from ..container import TraceError
from .base import BLOCK_ROWS, Block, ChannelInfo, SourceInfo, cause, need, read_path
from .channel_map import SourceOptions
from .mdf_links import check

__all__ = ["MdfSource"]




class MdfSource:
    """An MDF file; a channel's group is its channel group's acquisition name (or
    ``group N``)."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        asammdf = need("asammdf", "ASAM MDF files")
        self.path = read_path(path)
        check(self.path)
        try:
            self.mdf = asammdf.MDF(str(self.path))
        except Exception as exc:          # noqa: BLE001 - asammdf raises many kinds on a bad file
            raise TraceError(f"{self.path}: not a readable MDF file ({cause(exc)})") from None
        chans = []
        self.index: dict[tuple[str, str], tuple[int, int]] = {}
        self.groups: dict[str, int] = {}
        for g, group in enumerate(self.mdf.groups):
            label = getattr(group.channel_group, "acq_name", "") or f"group {g}"
            self.groups[label] = g
            n = int(group.channel_group.cycles_nr)
            rate, start = self._rate(g, n)
            master = self.mdf.masters_db.get(g)
            for c, ch in enumerate(group.channels):
                if c == master:
                    continue
                chans.append(ChannelInfo(name=ch.name, group=label, unit=ch.unit or None,
                                         samples=n, rate=rate, start=start))
                self.index[(label, ch.name)] = (g, c)
        self.info = SourceInfo(path=self.path, format="mf4", channels=tuple(chans),
                               notes=(f"MDF {self.mdf.version}, {len(self.mdf.groups)} channel "
                                      "group(s), each on its own master time base",),
                               own_time=True)

    def _rate(self, g: int, n: int) -> tuple[float | None, float | None]:
        if n < 2:
            return None, None
        t = np.asarray(self.mdf.get_master(g, record_offset=0, record_count=min(n, 1000)),
                       dtype=np.float64)
        step = float(np.median(np.diff(t))) if t.size > 1 else 0.0
        return (1.0 / step if step > 0 else None), float(t[0])

    def _read(self, info: ChannelInfo, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
        g, c = self.index[(info.group, info.name)]
        sig = self.mdf.get(group=g, index=c, record_offset=a, record_count=max(b - a, 0))
        return (np.asarray(sig.timestamps, dtype=np.float64),
                np.asarray(sig.samples, dtype=np.float64))

    def _on(self, info: ChannelInfo, t: np.ndarray) -> np.ndarray:
        """``info``'s samples (another group) interpolated onto the times ``t``; up to one of
        its own sample steps past its first or last record, its edge value is held (a group
        at a lower rate ends up to a step before the master's last record)."""
        n = info.samples or 0
        slack = 1.0 / info.rate if info.rate else 0.0
        if info.rate and info.start is not None:
            a = max(0, int(math.floor((t[0] - info.start) * info.rate)) - 2)
            b = min(n, int(math.ceil((t[-1] - info.start) * info.rate)) + 3)
            ts, x = self._read(info, a, b)
            if ts.size and ts[0] <= t[0] + slack and ts[-1] >= t[-1] - slack \
                    and (a == 0 or ts[0] <= t[0]) and (b == n or ts[-1] >= t[-1]):
                return np.interp(t, ts, x)
        ts, x = self._read(info, 0, n)
        if not ts.size or ts[0] > t[0] + slack or ts[-1] < t[-1] - slack:
            raise TraceError(f"{self.path}: channel {info.label} covers {ts[0] if ts.size else 0:.6g} "
                             f"to {ts[-1] if ts.size else 0:.6g} s, not the {t[0]:.6g} to "
                             f"{t[-1]:.6g} s of the master time base; cut the window inside "
                             "both (--window)")
        return np.interp(t, ts, x)

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        ref = channels[0]
        n = ref.samples or 0
        stop = n if stop is None else min(stop, n)
        for a in range(first, stop, BLOCK_ROWS):
            b = min(a + BLOCK_ROWS, stop)
            t, x0 = self._read(ref, a, b)
            cols = [x0]
            for info in channels[1:]:
                if info.group == ref.group:
                    cols.append(self._read(info, a, b)[1])
                else:
                    cols.append(self._on(info, t))
            yield Block(start=a, columns=tuple(cols), t=t)

    def close(self) -> None:
        self.mdf.close()
