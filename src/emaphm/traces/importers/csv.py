"""CSV exports: ``,`` ``;`` or tab between the fields, decimal points or commas, a units
row, quoted headers, ``name [unit]`` headers, and a preamble of comment or text lines
above the header; streamed in blocks by pyarrow (:func:`emaphm.traces.csv_format.csv_blocks`).
A column of text (a status or an event column) is listed, with a value, and never read;
a ``[source] delimiter`` or ``decimal`` of the map is checked against what the file looks
like, and a refusal says both."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

from ..container import TraceError
from ..csv_format import CsvLayout, is_number, is_text, csv_blocks, sniff_csv
from .base import Block, ChannelInfo, SourceInfo, read_path
from .channel_map import SourceOptions

__all__ = ["CsvSource"]


def _layout(path: Path, options: SourceOptions, delimiter: str | None,
            decimal: str | None) -> tuple[CsvLayout, str]:
    encodings = [options.encoding] if options.encoding else ["utf-8", "latin-1"]
    for k, encoding in enumerate(encodings):
        try:
            return sniff_csv(path, preamble=True, delimiter=delimiter, decimal=decimal,
                             encoding=encoding), encoding
        except UnicodeDecodeError:
            if k == len(encodings) - 1:
                raise
    raise AssertionError("unreachable")


def _delimiter_name(d: str) -> str:
    return "tab" if d == "\t" else repr(d)


def _mismatch(options: SourceOptions, guess: CsvLayout | None) -> tuple[str, str] | None:
    """Where the map's ``[source] delimiter`` or ``decimal`` is not what the file seems to
    use: ``(what the map says, what the file looks like and the fix)``."""
    if guess is None:
        return None
    given, fixes = [], []
    if options.delimiter is not None and options.delimiter != guess.delimiter:
        given.append(f"delimiter {_delimiter_name(options.delimiter)}")
        to = '"\\t"' if guess.delimiter == "\t" else repr(guess.delimiter)
        fixes.append(f"remove [source] delimiter or set it to {to}")
    shown = any(guess.decimal in c for r in guess.rows for c in r)   # rows of integers
    if options.decimal is not None and options.decimal != guess.decimal and shown:  # say none
        given.append(f"decimal {options.decimal!r}")
        fixes.append(f"remove [source] decimal or set it to {guess.decimal!r}")
    if not given:
        return None
    looks = (f"{_delimiter_name(guess.delimiter)} between the fields with decimal "
             f"{'comma' if guess.decimal == ',' else 'point'}")
    return " and ".join(given) + " from the map", f"the file looks like {looks}: " + \
        " and ".join(fixes)


def _text_columns(lay: CsvLayout) -> list[str | None]:
    """A value of each column that holds text and no number in the rows sniffed (a status
    or an event column), else None."""
    out: list[str | None] = []
    for k in range(len(lay.names)):
        cells = [r[k] for r in lay.rows if k < len(r)]
        text = next((c for c in cells if is_text(c, lay.decimal)), None)
        out.append(None if any(is_number(c, lay.decimal) for c in cells if c.strip()) else text)
    return out


class CsvSource:
    """A CSV export: one channel per column, named by its header cell."""

    def __init__(self, path: str | Path, options: SourceOptions = SourceOptions()) -> None:
        self.path = read_path(path)
        given = options.delimiter is not None or options.decimal is not None
        try:
            self.layout, encoding = _layout(self.path, options, options.delimiter,
                                            options.decimal)
        except TraceError:
            if not given:
                raise
            bad = _mismatch(options, self._guess(options))
            if bad is None:
                raise
            raise TraceError(f"{self.path}: with {bad[0]} no row splits into numbers; "
                             f"{bad[1]}") from None
        guess = self._guess(options) if given else None
        bad = _mismatch(options, guess)
        if bad and guess.header_line != self.layout.header_line:
            raise TraceError(f"{self.path}: with {bad[0]} the header is taken from line "
                             f"{self.layout.header_line + 1}, not {guess.header_line + 1}, as the "
                             f"rows do not split into numbers; {bad[1]}")
        hint = f"{bad[0]}, but {bad[1]}" if bad else ""
        lay = self.layout
        notes = [f"fields separated by {_delimiter_name(lay.delimiter)}",
                 f"decimal {'comma' if lay.decimal == ',' else 'point'}",
                 f"header on line {lay.header_line + 1}"]
        if lay.preamble:
            notes.append(f"{len(lay.preamble)} line(s) of preamble above it")
        if any(lay.units):
            notes.append("units from the header")
        if encoding != "utf-8":
            notes.append(f"text encoding {encoding}")
        text = _text_columns(lay)
        if any(text):
            notes.append("text, not read: " + ", ".join(repr(n) for n, x in zip(lay.names, text)
                                                        if x))
        if hint:
            notes.append(hint)
        self.info = SourceInfo(path=self.path, format="csv",
                               channels=tuple(ChannelInfo(name=n, unit=u, text=x)
                                              for n, u, x in zip(lay.names, lay.units, text)),
                               notes=tuple(notes), hint=hint)

    def _guess(self, options: SourceOptions) -> CsvLayout | None:
        """The layout the file has by its own look (without the map's delimiter and decimal)."""
        try:
            return _layout(self.path, options, None, None)[0]
        except (TraceError, UnicodeDecodeError):
            return None

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        names = list(self.layout.names)
        cols = [names.index(c.name) for c in channels]
        try:
            for start, arrays in csv_blocks(self.layout, cols, max_rows=None):
                if stop is not None and start >= stop:
                    return
                yield Block(start=start, columns=tuple(arrays))
        except TraceError as exc:
            if not self.info.hint:
                raise
            raise TraceError(f"{exc}; {self.info.hint}") from None

    def close(self) -> None:
        pass
