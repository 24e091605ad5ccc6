"""The Parquet trace format: one float64 column per quantity, the metadata JSON in the
schema metadata under the key ``b"emaphm"`` and the format version under
``b"emaphm-trace"``. pyarrow is imported when a Parquet file is read or written."""

from __future__ import annotations

import os
from pathlib import Path
from typing import IO

import numpy as np

from .container import COLUMNS, OPTIONAL_COLUMNS, UNITS, Trace, TraceError, _require_columns
from .limits import check_file_size, check_samples
from .metadata import FORMAT_VERSION, _dumps, _loads

_PARQUET_META_KEY = b"emaphm"
_PARQUET_VERSION_KEY = b"emaphm-trace"


def _write_parquet(trace: Trace, fh: IO[bytes]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    cols = trace.columns()
    schema = pa.schema(
        [pa.field(name, pa.float64(), nullable=False) for name in cols],
        metadata={
            _PARQUET_META_KEY: _dumps(trace.meta).encode("ascii"),
            _PARQUET_VERSION_KEY: str(FORMAT_VERSION).encode("ascii"),
        },
    )
    table = pa.table({name: pa.array(v, type=pa.float64()) for name, v in cols.items()},
                     schema=schema)
    pq.write_table(table, fh)


def _read_parquet(path: Path) -> tuple[dict[str, np.ndarray], dict]:
    import pyarrow as pa

    check_file_size(path)
    with pa.OSFile(os.fsencode(path)) as stream:        # bytes: any name the OS holds
        return _read_parquet_stream(stream, str(path))


def _read_parquet_stream(stream, source: str) -> tuple[dict[str, np.ndarray], dict]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        file = pq.ParquetFile(stream)
        schema, rows = file.schema_arrow, file.metadata.num_rows
    except (pa.ArrowInvalid, OSError) as exc:
        raise TraceError(f"{source}: not a readable Parquet file ({exc})") from None
    check_samples(rows, source)
    raw = (schema.metadata or {})
    version = raw.get(_PARQUET_VERSION_KEY)
    if version is not None and version.isdigit() and int(version) > FORMAT_VERSION:
        raise TraceError(
            f"{source}: written in emaphm trace format {version.decode()}, this version "
            f"reads format {FORMAT_VERSION}; upgrade emaphm"
        )
    meta = _loads(raw[_PARQUET_META_KEY], source) if _PARQUET_META_KEY in raw else {}
    names = list(schema.names)
    _require_columns(names, source)
    wanted = [c for c in COLUMNS + OPTIONAL_COLUMNS if c in names]
    table = file.read(columns=wanted)
    columns = {}
    for name in wanted:
        col = table.column(name)
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
            raise TraceError(
                f"{source}: column '{name}' has type {col.type}, expected numbers in "
                f"{UNITS[name]}; store it as float64"
            )
        # nulls become NaN, which validation reports with their row
        columns[name] = col.to_numpy(zero_copy_only=False).astype(np.float64)
    return columns, meta
