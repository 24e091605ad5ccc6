"""What every trace file format stores beside the signals: the format version and the
metadata as one JSON object."""

from __future__ import annotations

import json

from .container import TraceError

__all__ = ["FORMAT_VERSION"]

#: Format version written in the CSV first line and the Parquet schema metadata.
FORMAT_VERSION = 1

#: Largest metadata accepted: emaphm writes a few kB (parameters, profile, sensors), so a
#: larger block is not ours, or damaged, and is refused before it is parsed.
MAX_METADATA_BYTES = 1 << 20


def _dumps(meta: dict) -> str:
    # ensure_ascii keeps the CSV metadata on one ASCII line whatever the strings hold.
    return json.dumps(meta, ensure_ascii=True, allow_nan=True)


def _loads(text: str | bytes, source: str) -> dict:
    if len(text) > MAX_METADATA_BYTES:
        raise TraceError(
            f"{source}: the emaphm metadata is {len(text):,} bytes, above the "
            f"{MAX_METADATA_BYTES:,} a trace's metadata can be; it is not emaphm's or it is "
            "damaged: delete it (the data columns can still be read without it)"
        )
    try:
        meta = json.loads(text)
    except json.JSONDecodeError as exc:
        raise TraceError(
            f"{source}: the emaphm metadata is not valid JSON ({exc}); repair or delete "
            "the metadata (the data columns can still be read without it)"
        ) from None
    if not isinstance(meta, dict):
        raise TraceError(
            f"{source}: the emaphm metadata is a JSON {type(meta).__name__}, expected a "
            "JSON object; repair or delete the metadata"
        )
    return meta
