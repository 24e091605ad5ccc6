"""How large a trace may be: samples per trace and bytes per trace file, checked before and
while a file is read, so that a huge or endless file is refused with the limit in the
message instead of filling the memory.

A diagnosis needs one test profile (0.5 s, a few thousand samples); the limits leave two
orders of magnitude above that. Reading a trace at the limit keeps about
:data:`PEAK_BYTES_PER_SAMPLE` bytes per sample resident at its peak (measured by
``benchmarks/bench_import.py``; the trace itself holds 56, or 64 with a torque).
"""

from __future__ import annotations

import os
from pathlib import Path

from .container import TraceError

__all__ = ["MAX_SAMPLES", "MAX_FILE_BYTES", "check_file_size", "too_many_samples",
           "check_samples", "TooManySamples"]

#: Most samples a trace may have: 100 s at 20 kHz, 250 s at the preset's 8 kHz.
MAX_SAMPLES = 2_000_000
#: Largest trace file (CSV or Parquet) read: a 2,000,000-row CSV written by emaphm takes
#: about 280 MB.
MAX_FILE_BYTES = 512 * 1024 * 1024
#: Peak resident bytes per sample while a CSV trace is read and validated, measured on
#: 2,000,000 rows (BENCHMARKS.md, the import section: 616 MB, 308 bytes per sample, the
#: Python process and its libraries included): the parsed blocks, the trace's arrays and
#: the validation's temporaries; 5.5 times the 56 bytes of the trace itself.
PEAK_BYTES_PER_SAMPLE = 310


def _mb(n: int) -> str:
    return f"{n / 1e6:,.0f} MB"


def check_file_size(path: str | os.PathLike[str], limit: int = MAX_FILE_BYTES) -> int:
    """The size of ``path`` in bytes; :class:`TraceError` above ``limit``, before a byte of
    it is read."""
    size = Path(path).stat().st_size
    if size > limit:
        raise TraceError(
            f"{path}: the file is {_mb(size)}, above the {_mb(limit)} a trace file may be (at "
            f"most {MAX_SAMPLES:,} samples); a diagnosis needs one test profile (0.5 s): cut "
            "the test out of the recording with `emaphm import FILE --map MAP.toml --window "
            "START:END --out TRACE.parquet`")
    return size


class TooManySamples(TraceError):
    """:func:`too_many_samples`' error; ``found`` and ``limit`` kept for a reader of other
    files (a profile) to say it in its own words."""

    def __init__(self, message: str, found: str, limit: int) -> None:
        super().__init__(message)
        self.found, self.limit = found, limit


def too_many_samples(source: str, found: str, limit: int = MAX_SAMPLES) -> TooManySamples:
    """The error for a trace of more than ``limit`` samples (``found`` says how many)."""
    return TooManySamples(
        f"{source}: {found}, above the {limit:,} samples a trace may have (100 s at 20 kHz); "
        "a diagnosis needs one test profile (0.5 s): cut the test out of the recording with "
        "`emaphm import FILE --map MAP.toml --window START:END --out TRACE.parquet`",
        found, limit)


def check_samples(n: int, source: str, limit: int = MAX_SAMPLES) -> int:
    """``n`` if at most ``limit`` samples, else :func:`too_many_samples`."""
    if n > limit:
        raise too_many_samples(source, f"{n:,} samples", limit)
    return n
