"""CSV exports: ``,`` ``;`` or tab between the fields, decimal points or commas, a units
row, quoted headers, ``name [unit]`` headers, and a preamble of comment or text lines
above the header; streamed in blocks by pyarrow (:func:`emaphm.traces.csv_format.csv_blocks`)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

from ..csv_format import CsvLayout, csv_blocks, sniff_csv
from .base import Block, ChannelInfo, SourceInfo, read_path
from .channel_map import SourceOptions

__all__ = ["CsvSource"]




def _layout(path: Path, options: SourceOptions) -> tuple[CsvLayout, str]:
    encodings = [options.encoding] if options.encoding else ["utf-8", "latin-1"]
    for k, encoding in enumerate(encodings):
        try:
            return sniff_csv(path, preamble=True, delimiter=options.delimiter,
                             decimal=options.decimal, encoding=encoding), encoding
        except UnicodeDecodeError:
            if k == len(encodings) - 1:
                raise
    raise AssertionError("unreachable")


class CsvSource:
    """A CSV export: one channel per column, named by its header cell."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        self.path = read_path(path)
        self.layout, encoding = _layout(self.path, options)
        lay = self.layout
        notes = [f"fields separated by {'tab' if lay.delimiter == chr(9) else repr(lay.delimiter)}",
                 f"decimal {'comma' if lay.decimal == ',' else 'point'}",
                 f"header on line {lay.header_line + 1}"]
        if lay.preamble:
            notes.append(f"{len(lay.preamble)} line(s) of preamble above it")
        if any(lay.units):
            notes.append("units from the header")
        if encoding != "utf-8":
            notes.append(f"text encoding {encoding}")
        self.info = SourceInfo(path=self.path, format="csv",
                               channels=tuple(ChannelInfo(name=n, unit=u)
                                              for n, u in zip(lay.names, lay.units)),
                               notes=tuple(notes))

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        names = list(self.layout.names)
        cols = [names.index(c.name) for c in channels]
        for start, arrays in csv_blocks(self.layout, cols, max_rows=None):
            if stop is not None and start >= stop:
                return
            yield Block(start=start, columns=tuple(arrays))

    def close(self) -> None:
        pass
