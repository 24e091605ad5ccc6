"""The time column as recorders write it: a clock time (Unix epoch) instead of a test time,
and an export that stops before its test profile ends. Both are read, and said."""

from __future__ import annotations

import math
import warnings
from datetime import datetime, timezone

import numpy as np

from .container import Trace, TraceError, TraceWarning

__all__ = ["EPOCH_START_S", "from_epoch", "warn_if_shorter_than_profile"]

#: A trace whose time starts above this many seconds (about 3 years) holds clock times,
#: not the time of a test: recorders write Unix times (1.7e9 s in 2023).
EPOCH_START_S = 1e8
#: A time column that starts above this many seconds (the year 2286) is no clock's.
MAX_CLOCK_S = 1e10


def _when(t0: float) -> str:
    try:
        return datetime.fromtimestamp(t0, tz=timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    except (OverflowError, OSError, ValueError):
        return "beyond the calendar"


def from_epoch(t: np.ndarray, source: str) -> tuple[np.ndarray, float | None]:
    """``(t, None)`` for a test time; for clock times (``t[0] > EPOCH_START_S``) the times
    shifted to start at 0 and the start, with a :class:`TraceWarning` that says so.

    A clock time of 1.7e9 s keeps about 0.24 us of resolution in a double: where the steps
    scatter by no more than that, they are put on the uniform grid they were recorded on.
    """
    if t.size < 2 or not math.isfinite(float(t[0])) or float(t[0]) <= EPOCH_START_S:
        return t, None
    t0 = float(t[0])
    if t0 > MAX_CLOCK_S:
        raise TraceError(f"{source}: column 't' starts at {t0:.4g} s, beyond the {MAX_CLOCK_S:g} s "
                         "(the year 2286) of any clock: it holds no time of a test; check the "
                         "export")
    shifted = t - t0
    steps = np.diff(shifted)
    dt = float(shifted[-1]) / (t.size - 1)
    resolution = float(np.spacing(max(abs(float(t[-1])), abs(t0))))
    snapped = ""
    if np.all(steps > 0) and float(np.max(np.abs(steps - dt))) <= 2.0 * resolution:
        shifted = np.arange(t.size) * dt
        snapped = (f"; its steps, scattered by the {resolution * 1e6:.2g} us resolution of a "
                   "clock time, were put on their uniform grid")
    warnings.warn(TraceWarning(
        f"{source}: column 't' holds clock times (starts at {t0:.10g} s, a Unix time: "
        f"{_when(t0)}); shifted to start at 0 (the start is kept in the metadata as "
        f"t_start){snapped}"), stacklevel=3)
    shifted.setflags(write=False)
    return shifted, t0


def warn_if_shorter_than_profile(trace: Trace, source: str) -> bool:
    """Warn (:class:`TraceWarning`) when ``trace`` ends before the test profile its
    metadata names: the end of the test is missing. Returns whether it warned."""
    prof = trace.meta.get("profile")
    duration = prof.get("duration") if isinstance(prof, dict) else None
    if isinstance(duration, bool) or not isinstance(duration, (int, float)) \
            or not math.isfinite(duration) or trace.n < 2:
        return False
    if trace.duration + 1.5 * trace.dt >= float(duration):
        return False
    name = prof.get("name") if isinstance(prof.get("name"), str) else "its"
    warnings.warn(TraceWarning(
        f"{source}: the trace lasts {trace.duration:.4g} s, shorter than its test profile "
        f"({name[:40]}, {float(duration):.4g} s): the end of the test is missing, and a "
        "diagnosis reads only what was recorded; export the whole test"), stacklevel=3)
    return True
