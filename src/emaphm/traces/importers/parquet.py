"""Parquet exports: one channel per numeric column, read by row groups (pyarrow)."""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from ..container import TraceError
from .base import BLOCK_ROWS, Block, ChannelInfo, SourceInfo, cause, read_path
from .channel_map import SourceOptions

__all__ = ["ParquetSource"]




class ParquetSource:
    """A Parquet table: its numeric columns are the channels."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        self.path = read_path(path)
        try:
            self.stream = pa.OSFile(os.fsencode(self.path))      # bytes: any name the OS holds
        except OSError as exc:
            raise TraceError(f"{self.path}: cannot be opened ({cause(exc)})") from None
        try:
            self.file = pq.ParquetFile(self.stream)
        except (pa.ArrowInvalid, OSError) as exc:
            self.stream.close()
            raise TraceError(f"{self.path}: not a readable Parquet file ({cause(exc)})") from None
        schema = self.file.schema_arrow
        n = self.file.metadata.num_rows
        chans = [ChannelInfo(name=f.name, samples=n) for f in schema
                 if pa.types.is_floating(f.type) or pa.types.is_integer(f.type)]
        self.info = SourceInfo(path=self.path, format="parquet", channels=tuple(chans),
                               notes=(f"{n:,} rows in {self.file.num_row_groups} row group(s)",))

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        meta = self.file.metadata
        row = 0
        groups = []
        starts = []
        for g in range(meta.num_row_groups):
            size = meta.row_group(g).num_rows
            if row + size > first and (stop is None or row < stop):
                groups.append(g)
                starts.append(row)
            row += size
        names = [c.name for c in channels]
        for g, start in zip(groups, starts):
            for batch in self.file.iter_batches(batch_size=BLOCK_ROWS, row_groups=[g],
                                                columns=names):
                cols = tuple(batch.column(k).to_numpy(zero_copy_only=False).astype(np.float64)
                             for k in range(batch.num_columns))
                yield Block(start=start, columns=cols)
                start += batch.num_rows

    def close(self) -> None:
        self.file.close()
        self.stream.close()
