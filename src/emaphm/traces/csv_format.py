"""The CSV trace format: first line ``# emaphm-trace 1 {json metadata}``, a header row,
one row per sample written with ``repr`` of each float. The reader also takes bench
exports: no metadata line, columns in any order, extra columns ignored, ``;`` or tab
delimiters, names written as ``name [unit]`` and an optional units row."""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import IO

import numpy as np

from .container import COLUMNS, OPTIONAL_COLUMNS, UNITS, Trace, TraceError, _require_columns
from .metadata import FORMAT_VERSION, _dumps, _loads
from .validation import _normalise_unit, _unbracket

_CSV_MAGIC = "# emaphm-trace"


def _csv_chunks(trace: Trace, rows_per_chunk: int = 8192) -> Iterator[bytes]:
    cols = trace.columns()
    yield f"{_CSV_MAGIC} {FORMAT_VERSION} {_dumps(trace.meta)}\n".encode("ascii")
    yield (",".join(cols) + "\n").encode("ascii")
    data = np.column_stack(list(cols.values())) if trace.n else np.empty((0, len(cols)))
    for start in range(0, trace.n, rows_per_chunk):
        rows = data[start:start + rows_per_chunk].tolist()
        # repr(float) is the shortest string that reads back to the same double.
        text = "".join(",".join(map(repr, row)) + "\n" for row in rows)
        yield text.encode("ascii")


def _write_csv(trace: Trace, fh: IO[bytes]) -> None:
    for chunk in _csv_chunks(trace):
        fh.write(chunk)


_HEADER_UNIT = re.compile(r"^(?P<name>.*?)\s*(?P<unit>\[[^\]]*\]|\([^)]*\))$")


def _split_name(cell: str) -> tuple[str, str | None]:
    cell = cell.strip().strip('"').strip("'").strip()
    m = _HEADER_UNIT.match(cell)
    if m and m.group("name"):
        return m.group("name").strip(), m.group("unit")
    return cell, None


def _is_number(text: str) -> bool:
    try:
        float(text.strip().strip('"'))
    except ValueError:
        return False
    return True


def _read_csv(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    source = str(path)
    meta: dict = {}
    header: str | None = None
    consumed = 0
    units_row: list[str] | None = None
    with open(path, encoding="utf-8-sig", newline=None) as fh:
        for line in fh:
            consumed += 1
            s = line.strip()
            if not s:
                continue
            if s.startswith("#"):
                body = s[1:].strip()
                if body.startswith("emaphm-trace"):
                    parts = body[len("emaphm-trace"):].strip().split(maxsplit=1)
                    if not parts or not parts[0].isdigit():
                        raise TraceError(
                            f"{source}: malformed first line {s[:60]!r}; expected "
                            f"'{_CSV_MAGIC} {FORMAT_VERSION} {{json}}'"
                        )
                    if int(parts[0]) > FORMAT_VERSION:
                        raise TraceError(
                            f"{source}: written in emaphm trace format {parts[0]}, this "
                            f"version reads format {FORMAT_VERSION}; upgrade emaphm"
                        )
                    meta = _loads(parts[1], source) if len(parts) > 1 else {}
                continue
            header = s
            break
        if header is None:
            raise TraceError(
                f"{source}: no header row found; the first non-comment line must name the "
                f"columns, e.g. '{','.join(COLUMNS)}'"
            )
        counts = {d: header.count(d) for d in (",", ";", "\t")}
        delimiter = max(counts, key=counts.get) if max(counts.values()) else ","
        cells = header.split(delimiter)
        if all(_is_number(c) for c in cells):
            raise TraceError(
                f"{source}: the first row holds numbers, not column names; add a header "
                f"row '{','.join(COLUMNS)}'"
            )
        for line in fh:
            s = line.strip()
            if not s or s.startswith("#"):
                consumed += 1
                continue
            row = [c.strip().strip('"').strip() for c in s.split(delimiter)]
            if all(not c or c[0] + c[-1] in ("[]", "()") for c in row):
                units_row = row
                consumed += 1
            break

    names: list[str] = []
    units: dict[str, str] = {}
    for k, cell in enumerate(cells):
        name, unit = _split_name(cell)
        names.append(name)
        if units_row is not None and k < len(units_row) and units_row[k]:
            unit = units_row[k]
        if unit is not None and name in UNITS and _unbracket(unit):
            units[name] = _unbracket(unit)
    dupes = sorted({n for n in names if n in UNITS and names.count(n) > 1})
    if dupes:
        raise TraceError(f"{source}: column(s) {dupes} appear more than once; keep one each")
    _require_columns(names, source)

    wanted = [c for c in COLUMNS + OPTIONAL_COLUMNS if c in names]
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*input contained no data.*")
        try:
            data = np.loadtxt(
                path,
                dtype=np.float64,
                delimiter=delimiter,
                comments="#",
                skiprows=consumed,
                usecols=[names.index(c) for c in wanted],
                ndmin=2,
                encoding="utf-8",
                quotechar='"',
            )
        except ValueError as exc:
            where = ""
            m = re.search(r"at row (\d+), column (\d+)", str(exc))
            if m and 0 < int(m.group(2)) <= len(names):  # numpy: row from 0, column from 1
                where = f" in data row {m.group(1)}, column '{names[int(m.group(2)) - 1]}'"
            raise TraceError(
                f"{source}: cannot read the data as numbers{where} ({exc}); every data row "
                f"needs a number in each of the columns {wanted} (write missing values as "
                "'nan')"
            ) from None
    columns = {name: data[:, k] for k, name in enumerate(wanted)}

    if units:
        declared = meta.get("units")
        if isinstance(declared, Mapping):
            for name, unit in units.items():
                other = declared.get(name)
                if isinstance(other, str) and _normalise_unit(other) != _normalise_unit(unit):
                    raise TraceError(
                        f"{source}: column '{name}' is declared in '{other}' by the "
                        f"metadata but in '{unit}' by the header; make them agree"
                    )
            meta["units"] = {**declared, **units}
        else:
            meta["units"] = units
    return columns, meta
