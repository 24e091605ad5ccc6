"""The CSV trace format: first line ``# emaphm-trace 1 {json metadata}``, a header row,
one row per sample, each float written as the shortest text that reads back to the same
double. The reader also takes bench exports: no metadata line, columns in any order,
extra columns ignored, ``;`` or tab delimiters, names written as ``name [unit]`` and an
optional units row.

Reading is streamed: :func:`sniff_csv` reads the first lines (metadata, header, units row,
delimiter, decimal mark) into a :class:`CsvLayout`, and :func:`csv_blocks` parses the data
in blocks with pyarrow's streaming CSV reader, counting the rows against a limit, so that
memory follows the columns kept, not the file. The bench importer
(:mod:`emaphm.traces.importers`) reads its CSV exports through the same two functions.
"""

from __future__ import annotations

import csv
import os
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import numpy as np

from .container import COLUMNS, OPTIONAL_COLUMNS, UNITS, Trace, TraceError, _require_columns
from .limits import MAX_SAMPLES, check_file_size, too_many_samples
from .metadata import FORMAT_VERSION, _dumps, _loads
from .validation import _import_command, _normalise_symbol, _unbracket

__all__ = ["CsvLayout", "sniff_csv", "csv_blocks", "is_number", "is_text"]

_CSV_MAGIC = "# emaphm-trace"
#: Lines :func:`sniff_csv` reads at most to find the header (a bench export's preamble
#: of comment lines included).
SNIFF_LINES = 1000
#: Data rows :func:`sniff_csv` keeps to judge the delimiter and the decimal mark.
SNIFF_ROWS = 20
#: Bytes pyarrow parses per block.
BLOCK_BYTES = 1 << 22
_DECIMAL_COMMA = re.compile(r"^[-+]?\d+,\d+(?:[eE][-+]?\d+)?$")


# ----------------------------------------------------------------------------- writing
def _csv_chunks(trace: Trace, rows_per_chunk: int = 65536) -> Iterator[bytes]:
    """The file in chunks: the metadata line, the header, then blocks of rows written by
    pyarrow's CSV writer (vectorized; each double as the shortest text that reads back to
    it, as ``repr`` gives it up to its spelling: ``1e-05`` is written ``0.00001``)."""
    import io

    import pyarrow as pa
    import pyarrow.csv as pcsv

    cols = trace.columns()
    yield f"{_CSV_MAGIC} {FORMAT_VERSION} {_dumps(trace.meta)}\n".encode("ascii")
    yield (",".join(cols) + "\n").encode("ascii")
    table = pa.table({name: pa.array(v, type=pa.float64()) for name, v in cols.items()})
    options = pcsv.WriteOptions(include_header=False, batch_size=rows_per_chunk)
    for start in range(0, trace.n, rows_per_chunk):
        buf = io.BytesIO()
        pcsv.write_csv(table.slice(start, rows_per_chunk), buf, options)
        yield buf.getvalue()


def _write_csv(trace: Trace, fh: IO[bytes]) -> None:
    for chunk in _csv_chunks(trace):
        fh.write(chunk)


# ----------------------------------------------------------------------------- layout
@dataclass(frozen=True)
class CsvLayout:
    """Where a CSV file's data are and how they are written.

    ``names`` and ``units`` (one per column; a unit from ``name [unit]`` or the units
    row, else None) describe the header row at physical line ``header_line``; the data
    start at byte ``data_offset``. ``rows`` holds the first data rows as text (for
    inspection); ``preamble`` the comment or text lines above the header.
    """

    path: Path
    delimiter: str
    decimal: str
    header_line: int
    data_offset: int
    names: tuple[str, ...]
    units: tuple[str | None, ...]
    meta: dict = field(default_factory=dict)
    rows: tuple[tuple[str, ...], ...] = ()
    preamble: tuple[str, ...] = ()
    encoding: str = "utf-8"


def _split(line: str, delimiter: str) -> list[str]:
    line = line.replace("\r", " ").replace("\x00", "")
    try:
        cells = next(csv.reader([line], delimiter=delimiter, quotechar='"'), [])
    except csv.Error:
        cells = line.split(delimiter)
    return [c.strip() for c in cells]


def is_number(text: str, decimal: str = ".") -> bool:
    text = text.strip().strip('"')
    if decimal == ",":
        text = text.replace(",", ".")
    try:
        float(text)
    except ValueError:
        return False
    return True


_HEADER_UNIT = re.compile(r"^(?P<name>.*?)\s*(?P<unit>\[[^\]]*\]|\([^)]*\))$")


def _split_name(cell: str) -> tuple[str, str | None]:
    cell = cell.strip().strip('"').strip("'").strip()
    m = _HEADER_UNIT.match(cell)
    if m and m.group("name"):
        return m.group("name").strip(), _unbracket(m.group("unit"))
    return cell, None


def _metadata(body: str, source: str) -> dict:
    parts = body[len("emaphm-trace"):].strip().split(maxsplit=1)
    if not parts or not parts[0].isdigit():
        raise TraceError(f"{source}: malformed first line {('# ' + body)[:60]!r}; expected "
                         f"'{_CSV_MAGIC} {FORMAT_VERSION} {{json}}'")
    if int(parts[0]) > FORMAT_VERSION:
        raise TraceError(f"{source}: written in emaphm trace format {parts[0]}, this version "
                         f"reads format {FORMAT_VERSION}; upgrade emaphm")
    return _loads(parts[1], source) if len(parts) > 1 else {}


#: Longest line :func:`sniff_csv` reads (the metadata line is at most 1 MiB).
MAX_LINE_BYTES = 2 << 20
_NUMERIC_LINE = re.compile(r"^[\s\d.,;\t+\-eE\"]*\d[\s\d.,;\t+\-eEnaNA\"]*$")


_LINE_END = re.compile(rb"\r\n|\r|\n")


def _raw_lines(fh: IO[bytes], limit: int, chunk: int = 1 << 16) -> Iterator[bytes]:
    """The lines of ``fh`` with their endings: ``\\n``, ``\\r\\n`` or a lone ``\\r`` (an
    old Mac export, which pyarrow's parser reads too); a line longer than ``limit`` is
    yielded cut at ``limit + 1`` bytes, and no more after it."""
    buf, pos, start, eof = b"", 0, 0, False       # the line at buf[pos:] starts
    while True:
        m = _LINE_END.search(buf, start)
        if m is not None and (m.end() < len(buf) or eof or m.group() != b"\r"):
            if m.end() - pos > limit + 1:
                yield buf[pos:pos + limit + 1]
                return
            yield buf[pos:m.end()]
            pos = start = m.end()
            continue
        if eof or len(buf) - pos > limit:
            if len(buf) > pos:
                yield buf[pos:pos + limit + 1]
            return
        buf, start = buf[pos:], max(len(buf) - pos - 1, 0)   # a CR at the end may start a CRLF
        pos = 0
        data = fh.read(chunk)
        eof = not data
        buf += data


def _lines(path: Path, encoding: str) -> Iterator[tuple[int, int, str]]:
    """``(line index, byte offset after the line, text)`` of the first lines of ``path``."""
    offset = 0
    with open(path, "rb") as fh:
        for index, raw in zip(range(SNIFF_LINES), _raw_lines(fh, MAX_LINE_BYTES)):
            if len(raw) > MAX_LINE_BYTES:
                raise TraceError(f"{path}: line {index + 1} is longer than {MAX_LINE_BYTES:,} "
                                 "bytes: not a CSV text file (or its lines are not ended)")
            offset += len(raw)
            text = raw.decode(encoding).rstrip("\r\n")
            yield index, offset, text.lstrip("\ufeff") if index == 0 else text


def _guess_delimiter(line: str) -> str:
    """Tab or ``;`` where the line has them (a ``,`` beside them is a decimal comma or
    part of a name), else ``,``."""
    tabs, semicolons = line.count("\t"), line.count(";")
    if tabs or semicolons:
        return "\t" if tabs > semicolons else ";"
    return ","


def _looks_numeric(cells: Sequence[str], decimal: str) -> bool:
    return bool(cells) and all(is_number(c, decimal) or c.strip().lower() in ("", "nan")
                               for c in cells) and any(c.strip() for c in cells)


def is_text(cell: str, decimal: str) -> bool:
    """A cell that is neither a number nor empty (nor ``nan``)."""
    return cell.strip().lower() not in ("", "nan") and not is_number(cell, decimal)


def _data_like(cells: Sequence[str], decimal: str) -> bool:
    """A row of data in a bench export: its first cell a number (the time or the sample
    count: a preamble's ``Rate;10000`` starts with its name) and at least as many numbers
    as text cells (a status or event column of text beside the channels)."""
    filled = [c for c in cells if c.strip()]
    if len(cells) < 2 or not filled or not is_number(filled[0], decimal):
        return False
    numbers = sum(is_number(c, decimal) for c in filled)
    return numbers >= sum(is_text(c, decimal) for c in cells)


def _mostly_numbers(line: str) -> bool:
    """A line that looks like a row of data (for counting them while sniffing)."""
    cells = _split(line, _guess_delimiter(line))
    return _data_like(cells, ",") or _data_like(cells, ".")


def _is_symbols_row(cells: Sequence[str]) -> bool:
    """A units row: no numbers (but ``1``, a unit), and most of its cells units of the table
    or bracketed (``[degC]``); a unit the table lacks (``°C`` of a temperature) is that
    channel's own."""
    from ..quantities import QuantityError, measure

    filled = [c for c in cells if c.strip()]
    known = 0
    for c in filled:
        if is_number(c, ".") or is_number(c, ","):     # "1" is a unit, and a number: it
            continue                                     # counts for neither
        try:
            known += c[0] + c[-1] in ("[]", "()") or measure(c).kind != ""
        except QuantityError:
            pass
    return bool(filled) and 2 * known > len(filled) and not _looks_numeric(cells, ".")


def sniff_csv(path: str | Path, *, preamble: bool = False, delimiter: str | None = None,
              decimal: str | None = None, encoding: str = "utf-8") -> CsvLayout:
    """Read the first lines of a CSV file into a :class:`CsvLayout`.

    The header is the first line that is not a comment (``#``); with ``preamble=True``
    (bench exports) it is the last text line above the first rows of data, so that lines
    of text such as ``Sample rate: 20 kHz`` may precede it; a row of data may hold text
    in some columns (a status or an event column). ``delimiter`` (``,`` ``;`` tab) and
    ``decimal`` (``.`` or ``,``) are judged from the header and the first rows unless
    given. A units row (``[s];[A]`` or ``s;A``; with ``preamble=True`` one whose cells are
    mostly units, ``ms;deg;degC``) under the header is recognised.
    """
    path = Path(path)
    source = str(path)
    meta: dict = {}
    comments: list[str] = []
    candidates: list[tuple[int, int, str]] = []        # non-comment lines read so far
    numeric = 0
    for index, offset, text in _lines(path, encoding):
        s = text.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s[1:].strip()
            if body.startswith("emaphm-trace"):
                meta = _metadata(body, source)
            else:
                comments.append(s)
            continue
        candidates.append((index, offset, text))
        numeric += bool(_NUMERIC_LINE.match(s)) or (preamble and _mostly_numbers(s))
        if (numeric if preamble else len(candidates)) > SNIFF_ROWS + 1:
            break
    if not candidates:
        raise TraceError(f"{source}: no header row found; the first non-comment line must name "
                         f"the columns, e.g. '{','.join(COLUMNS)}'")
    return _layout(path, candidates, meta, comments, preamble=preamble, delimiter=delimiter,
                   decimal=decimal, encoding=encoding)


def _header_index(cands: list[tuple[int, int, str]], delimiter: str, decimal: str,
                  preamble: bool, source: str) -> int:
    """Index in ``cands`` of the header row."""
    if not preamble:
        return 0
    rows = [_split(c[2], delimiter) for c in cands]
    last = len(rows)                    # the rows of data at the end of those read
    while last > 1 and len(rows) - last < 5 and _data_like(rows[last - 1], decimal):
        last -= 1
    for k in range(1, len(cands)):
        cells = rows[k]
        # the first of (up to) three rows of data of one width: a text column beside the
        # channels, or an event column that has text in this row only, does not hide it;
        # text where the last rows read all have numbers is a preamble's ("Kanäle;6")
        tail = [r for r in rows[last:] if len(r) == len(cells)]
        if all(_data_like(r, decimal) and len(r) == len(cells) for r in rows[k:k + 3]) and \
                not any(is_text(c, decimal) and all(is_number(r[j], decimal) for r in tail)
                        for j, c in enumerate(cells)):
            head = k - 1
            if head >= 1 and _is_symbols_row(_split(cands[head][2], delimiter)) \
                    and len(_split(cands[head - 1][2], delimiter)) == len(cells):
                head -= 1
            return head
    raise TraceError(f"{source}: no rows of numbers found in the first {SNIFF_LINES} lines; "
                     "is it a CSV export of measured channels?")


def _layout(path: Path, cands: list[tuple[int, int, str]], meta: dict, comments: list[str], *,
            preamble: bool, delimiter: str | None, decimal: str | None,
            encoding: str) -> CsvLayout:
    source = str(path)
    if delimiter is None:
        # the delimiter of the first line that has one, judged on a row of data where a
        # header could be one column
        lines = [c[2] for c in cands]
        delimiter = _guess_delimiter(lines[-1] if preamble and len(lines) > 1 else lines[0])
    data_cells = [_split(c[2], delimiter) for c in cands[1:]]
    if decimal is None:
        decimal = ("," if delimiter != "," and any(_DECIMAL_COMMA.match(x) for row in data_cells
                                                    for x in row) else ".")
    h = _header_index(cands, delimiter, decimal, preamble, source)
    header_line, _, header = cands[h]
    cells = _split(header, delimiter)
    if all(is_number(c) for c in cells):
        raise TraceError(f"{source}: the first row holds numbers, not column names; add a "
                         f"header row '{','.join(COLUMNS)}'")
    rest = cands[h + 1:]
    data_offset = cands[h][1]
    units_row = None
    if rest:
        first = _split(rest[0][2], delimiter)
        if (all(not c or c[0] + c[-1] in ("[]", "()") for c in first)
                or (preamble and _is_symbols_row(first))):
            units_row, data_offset = first, rest[0][1]
            rest = rest[1:]
    names, units = [], []
    for k, cell in enumerate(cells):
        name, unit = _split_name(cell)
        if units_row is not None and k < len(units_row) and _unbracket(units_row[k]):
            unit = _unbracket(units_row[k])
        names.append(name)
        units.append(unit or None)
    return CsvLayout(path=path, delimiter=delimiter, decimal=decimal, header_line=header_line,
                     data_offset=data_offset, names=tuple(names), units=tuple(units), meta=meta,
                     rows=tuple(tuple(_split(c[2], delimiter)) for c in rest[:SNIFF_ROWS]),
                     preamble=tuple(comments) + tuple(c[2] for c in cands[:h]),
                     encoding=encoding)


# ----------------------------------------------------------------------------- data
def _bad_row(layout: CsvLayout, columns: Sequence[int]) -> str | None:
    """Where the data first cannot be read (the error path only: the file is scanned
    again from its data): ``" in data row 8, column 'omega_m' (...)"``."""
    nulls = {"", "nan", "NaN", "NAN", "-nan"}
    width = len(layout.names)
    with open(layout.path, encoding=layout.encoding, newline="") as fh:
        fh.seek(layout.data_offset)
        row = 0
        for cells in csv.reader(fh, delimiter=layout.delimiter, quotechar='"'):
            if not cells or not "".join(cells).strip():
                continue
            if len(cells) != width:
                comma = ("; the numbers look written with a decimal comma and ',' between the "
                         "fields too: export with ';' between the fields"
                         if len(cells) > width and layout.delimiter == "," else "")
                return (f" in data row {row}: it has {len(cells)} fields, the header "
                        f"{width}{comma}")
            for c in columns:
                text = cells[c].strip()
                if text not in nulls and not is_number(text, layout.decimal):
                    return f" in data row {row}, column '{layout.names[c]}' (the value {text[:40]!r})"
            row += 1
    return None


def _row_error(exc: Exception, layout: CsvLayout, columns: Sequence[int]) -> TraceError:
    """pyarrow's parse error as a TraceError naming the data row and the column."""
    detail = re.sub(r"^In CSV column #\d+: (Row #\d+: )?", "", str(exc).splitlines()[0])[:120]
    try:
        where = _bad_row(layout, columns)
    except (OSError, UnicodeDecodeError, csv.Error):
        where = None
    return TraceError(f"{layout.path}: cannot read the data as numbers{where or ''} ({detail}); "
                      f"every data row needs a number in each of the columns "
                      f"{[layout.names[c] for c in columns]}: correct that value in the file, or "
                      "remove its row")


def csv_blocks(layout: CsvLayout, columns: Sequence[int], *, max_rows: int | None = MAX_SAMPLES,
               block_bytes: int = BLOCK_BYTES) -> Iterator[tuple[int, list[np.ndarray]]]:
    """Parse the data of ``layout`` in blocks: ``(first data row, [float64 array per
    column])`` for the column indices ``columns``.

    Empty values and ``nan`` read as NaN (comment lines are read only above the header).
    More than ``max_rows`` rows raise :class:`TraceError` with the limit, as
    soon as the block that passes it is parsed.
    """
    import pyarrow as pa
    import pyarrow.csv as pcsv

    width = len(layout.names)
    names = [f"c{k}" for k in range(width)]
    if layout.path.stat().st_size <= layout.data_offset:
        return                                          # a header and no data
    stream = pa.OSFile(os.fsencode(layout.path))        # bytes: any name the OS holds
    stream.seek(layout.data_offset)
    try:
        reader = pcsv.open_csv(
            stream,
            read_options=pcsv.ReadOptions(column_names=names, block_size=block_bytes,
                                          encoding=layout.encoding),
            parse_options=pcsv.ParseOptions(delimiter=layout.delimiter, quote_char='"'),
            convert_options=pcsv.ConvertOptions(
                include_columns=[names[c] for c in columns],
                column_types={names[c]: pa.float64() for c in columns},
                decimal_point=layout.decimal, null_values=["", "nan", "NaN", "NAN", "-nan"],
                strings_can_be_null=False),
        )
        row = 0
        while True:
            try:
                batch = reader.read_next_batch()
            except StopIteration:
                return
            except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
                raise _row_error(exc, layout, columns) from None
            if max_rows is not None and row + batch.num_rows > max_rows:
                raise too_many_samples(f"{layout.path}", f"at least {row + batch.num_rows:,} rows",
                                       max_rows)
            yield row, [batch.column(k).to_numpy(zero_copy_only=False).astype(np.float64, copy=False)
                        for k in range(batch.num_columns)]
            row += batch.num_rows
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        raise _row_error(exc, layout, columns) from None
    finally:
        stream.close()


def collect(blocks: Iterator[tuple[int, list[np.ndarray]]], n_columns: int) -> list[np.ndarray]:
    """Concatenate the columns of ``blocks`` into read-only float64 arrays (a trace shares
    them, it does not copy them)."""
    parts: list[list[np.ndarray]] = [[] for _ in range(n_columns)]
    for _, cols in blocks:
        for k, c in enumerate(cols):
            parts[k].append(c)
    out = []
    for k in range(n_columns):
        arr = np.concatenate(parts[k]) if parts[k] else np.empty(0)
        parts[k] = []
        arr.setflags(write=False)
        out.append(arr)
    return out


# ----------------------------------------------------------------------------- the reader
def _decimal_comma_error(layout: CsvLayout) -> TraceError:
    sample = next((x for row in layout.rows for x in row if _DECIMAL_COMMA.match(x)), "")
    return TraceError(
        f"{layout.path}: the numbers are written with a decimal comma (e.g. {sample!r}) and "
        f"'{layout.delimiter}' between the fields, as a spreadsheet in a German or French "
        "locale exports them; an emaphm trace uses decimal points. Import the file as it is "
        f"with `emaphm import {layout.path.name} --inspect` (it reads decimal commas, units "
        "and channel names), or export it with decimal points")


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    source = str(path)
    check_file_size(path)
    layout = sniff_csv(path)
    if layout.decimal == ",":
        raise _decimal_comma_error(layout)
    meta = dict(layout.meta)
    names = list(layout.names)
    units = {n: u for n, u in zip(names, layout.units) if u and n in UNITS}
    dupes = sorted({n for n in names if n in UNITS and names.count(n) > 1})
    if dupes:
        raise TraceError(f"{source}: column(s) {dupes} appear more than once; keep one each")
    try:
        _require_columns(names, source)
    except TraceError as exc:           # a bench export's own channel names, most often
        raise TraceError(f"{exc}; or import the export as it is: "
                         f"{_import_command(path, '--inspect')} prints a channel map to edit "
                         "(names, units, decimal commas)") from None
    wanted = [c for c in COLUMNS + OPTIONAL_COLUMNS if c in names]
    arrays = collect(csv_blocks(layout, [names.index(c) for c in wanted]), len(wanted))
    columns = dict(zip(wanted, arrays))
    if units:
        declared = meta.get("units")
        if isinstance(declared, Mapping):
            for name, unit in units.items():
                other = declared.get(name)
                if isinstance(other, str) and _normalise_symbol(other) != _normalise_symbol(unit):
                    raise TraceError(
                        f"{source}: column '{name}' is declared in '{other}' by the "
                        f"metadata but in '{unit}' by the header; make them agree"
                    )
            meta["units"] = {**declared, **units}
        else:
            meta["units"] = units
    return columns, meta
