"""From a bench export and its channel map to an emaphm :class:`~emaphm.traces.Trace`:
pick the channels, convert them to SI, find the time base, keep the window, derive what
is missing (``omega_m`` from ``theta_m``, ``i_c`` from the other two), check what a
recorder gets wrong (channels of different length, a time base that goes back, NaN runs),
and say in the metadata where it all came from.

The export is read in blocks: memory holds the window kept (at most
:data:`~emaphm.traces.limits.MAX_SAMPLES` samples) and one block, however long the
recording."""

from __future__ import annotations

import hashlib
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..container import DRIVE_COLUMNS, Trace, TraceError, TraceWarning
from ..derive import derive_missing, derived_meta
from ..limits import MAX_SAMPLES, too_many_samples
from ..timebase import warn_if_shorter_than_profile
from ..validation import validate
from .base import ChannelInfo, SourceInfo, and_list
from .channel_map import ChannelMap, Conversion
from .registry import open_source

__all__ = ["import_trace", "Window", "file_digest"]

#: What no actuator's recording reaches, per column, in SI (a clock time of the year 2286,
#: 1.6 million turns, 950,000 rpm, 100 kA, 1 MN m): a channel beyond it is read in the wrong
#: unit, scale or offset (a current of 1e298 A was taken for one in mA).
_REACH = {"t": 1e10, "theta_ref": 1e7, "theta_m": 1e7, "omega_m": 1e5, "i_a": 1e5, "i_b": 1e5,
          "i_c": 1e5, "torque": 1e6,
          # what the drive logs: voltages of any DC link, duties, references
          **{f"v_{x}": 1e5 for x in "abcdq"}, "v_dc": 1e5, **{f"d_{x}": 1e3 for x in "abc"},
          "i_d_ref": 1e5, "i_q_ref": 1e5, "omega_ref": 1e5}
#: Order the channels are asked for: the first one's time base is an MDF file's master.
_ORDER = ("i_a", "i_b", "i_c", "theta_ref", "theta_m", "omega_m", "torque", "t") + DRIVE_COLUMNS
#: Relative spread of the time steps above which an import puts the samples on a uniform
#: grid (validation's own tolerance), and above which it refuses to.
_UNIFORM_RTOL = 1e-3
_RESAMPLE_LIMIT = 0.5


@dataclass(frozen=True)
class Window:
    """The part of a recording to import, ``start`` to ``end`` [s] of its own time (None:
    from its beginning, to its end)."""

    start: float | None = None
    end: float | None = None

    def __post_init__(self) -> None:
        for v in (self.start, self.end):
            if v is not None and not math.isfinite(v):
                raise TraceError(f"--window: times must be finite seconds, got {v!r}")
        if self.start is not None and self.end is not None and self.end <= self.start:
            raise TraceError(f"--window {self.start:g}:{self.end:g}: the end must come after the "
                             "start")

    @classmethod
    def parse(cls, text: str | None) -> "Window":
        """``"START:END"`` (seconds; either may be left out), as ``--window`` takes it."""
        if text is None:
            return cls()
        parts = text.split(":")
        try:
            if len(parts) != 2:
                raise ValueError
            lo, hi = (float(p) if p.strip() else None for p in parts)
        except ValueError:
            raise TraceError(f"--window {text[:40]!r}: expected START:END in seconds of the "
                             "recording, e.g. 12.5:13.0 (either may be left out)") from None
        return cls(lo, hi)

    def to_list(self) -> list[float | None]:
        return [self.start, self.end]


def file_digest(path: Path) -> str:
    """SHA-256 of the file's bytes, read in chunks."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


@dataclass(frozen=True)
class _TimeBase:
    mode: str                     # "channel", "rate" or "own"
    rate: float | None = None
    start: float = 0.0


def _time_base(cmap: ChannelMap, info: SourceInfo, chans: dict[str, ChannelInfo],
               where: str) -> _TimeBase:
    if "t" in chans:
        return _TimeBase("channel")
    if cmap.time.rate is not None:
        return _TimeBase("rate", cmap.time.rate, cmap.time.start)
    if info.own_time:
        ref = chans[_first(chans)]
        return _TimeBase("own", ref.rate, ref.start or 0.0)
    rates = {(c.rate, c.start) for c in chans.values()}
    if len(rates) == 1 and None not in next(iter(rates)):
        rate, start = next(iter(rates))
        return _TimeBase("rate", rate, start)
    if all(c.rate for c in chans.values()):
        by_rate = {c.rate for c in chans.values()}
        what, key = (("rates", lambda c: f"{c.rate:g} Hz") if len(by_rate) > 1
                     else ("start times", lambda c: f"t = {c.start:g} s"))
        groups: dict[str, list[str]] = {}
        for c in chans.values():
            groups.setdefault(key(c), []).append(repr(c.label))
        shown = "; ".join(f"{and_list(names)} at {k}" for k, names in groups.items())
        raise TraceError(f"{where}: the channels mapped have time bases at different {what} "
                         f"({shown}); emaphm needs them on one time base: record or export them "
                         "at one rate (or resample them in the recorder), or map channels of one "
                         "rate")
    raise TraceError(f"{where}: no time base: the file has no time for these channels; map a t "
                     "channel in [channels] or give the sample rate in [time] rate = ... (Hz)")


def _distinct(chans: dict[str, ChannelInfo], map_name: str) -> None:
    """Refuse two columns mapped to one channel (theta_m to the time channel read as a
    motion, theta_ref and theta_m to one position: a diagnosis of nonsense)."""
    seen: dict[str, str] = {}
    for target, c in chans.items():
        if c.label in seen:
            raise TraceError(f"{map_name}: [channels] {seen[c.label]} and {target} both name "
                             f"channel {c.label!r}; map each column to its own channel "
                             "(`emaphm import FILE --inspect` lists them)")
        seen[c.label] = target


def _first(chans: dict[str, ChannelInfo]) -> str:
    return next(t for t in _ORDER if t in chans)


def _check_lengths(chans: dict[str, ChannelInfo], base: _TimeBase, where: str) -> int | None:
    """The common number of samples (None where unknown before reading)."""
    known = {t: c.samples for t, c in chans.items() if c.samples is not None}
    if not known:
        return None
    if base.mode == "own":         # the master of the first channel's group: the others are
        return chans[_first(chans)].samples     # resampled onto it, whatever their length
    if len(set(known.values())) > 1 and base.mode != "own":
        same_base = {(c.rate, c.start) for c in chans.values()}
        if base.mode == "rate" and len(same_base) == 1 and None not in next(iter(same_base)):
            return min(known.values())          # waveforms on one time base: the common part
        sizes = ", ".join(f"{chans[t].label} ({t}) {n:,}" for t, n in known.items())
        raise TraceError(f"{where}: the channels have different lengths ({sizes} samples) and "
                         "no common time base; map channels recorded together (one group, one "
                         "rate), or resample them onto one time base in the recorder")
    return min(known.values())


def _rows(base: _TimeBase, window: Window, n: int | None) -> tuple[int, int | None]:
    """Rows to read where the time is a known rate (else all of them)."""
    if base.mode not in ("rate", "own") or not base.rate:
        return 0, n
    first = 0 if window.start is None else max(0, math.ceil((window.start - base.start)
                                                            * base.rate - 1e-6) - 1)
    stop = n if window.end is None else int(math.floor((window.end - base.start) * base.rate
                                                       + 1e-6)) + 2
    if n is not None and stop is not None:
        stop = min(stop, n)
    return first, stop


def _nan_runs(name: str, target: str, x: np.ndarray, t: np.ndarray, where: str) -> None:
    bad = np.isnan(x)
    if not bad.any():
        return
    first = int(np.argmax(bad))
    run = int(np.argmax(~bad[first:])) if (~bad[first:]).any() else int(bad.size - first)
    raise TraceError(f"{where}: channel {name!r} ({target}) has a run of {run:,} NaN sample(s) "
                     f"from t = {t[first]:.9g} s (row {first:,} of the window), {int(bad.sum()):,} "
                     "in all; import a window without them (--window START:END), or fill the "
                     "gap in the recorder")


class _Collector:
    """The window's rows, block by block, with the checks that need the whole stream."""

    def __init__(self, targets: Sequence[str], window: Window, limit: int, where: str,
                 span: tuple[float, float] | None = None) -> None:
        self.targets, self.window, self.limit, self.where = list(targets), window, limit, where
        self.known_span = span           # the recording's span where its rate tells it
        self.parts: dict[str, list[np.ndarray]] = {t: [] for t in targets}
        self.times: list[np.ndarray] = []
        self.kept = 0
        self.last_t = -math.inf
        self.span = [math.inf, -math.inf]
        self.done = False

    def add(self, t: np.ndarray, cols: dict[str, np.ndarray], first_row: int) -> None:
        if t.size == 0:
            return
        steps = np.diff(t)
        if not (t[0] > self.last_t) or (steps.size and not np.all(steps > 0)):
            k = 0 if not (t[0] > self.last_t) else int(np.argmax(~(steps > 0))) + 1
            before = self.last_t if k == 0 else t[k - 1]
            raise TraceError(f"{self.where}: the time base is not increasing: row {first_row + k:,} "
                             f"is at t = {t[k]:.9g} s, after {before:.9g} s (a recorder restart, "
                             "a wrapped counter or appended runs?); import a window before or "
                             "after it (--window START:END)")
        self.last_t = float(t[-1])
        self.span = [min(self.span[0], float(t[0])), float(t[-1])]
        lo, hi = self.window.start, self.window.end
        keep = np.ones(t.size, dtype=bool)
        if lo is not None:
            keep &= t >= lo
        if hi is not None:
            keep &= t <= hi
            self.done = bool(t[-1] > hi)
        n = int(keep.sum())
        if not n:
            return
        self.kept += n
        if self.kept > self.limit:
            raise too_many_samples(self.where, f"the import would hold more than {self.limit:,} "
                                   "samples", self.limit)
        self.times.append(t[keep])
        for target in self.targets:
            self.parts[target].append(cols[target][keep])

    def arrays(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        if not self.kept:
            lo, hi = self.span
            if self.known_span is not None and not lo <= hi:    # no row read: outside it
                lo, hi = self.known_span
            raise TraceError(f"{self.where}: no samples in the window {self.window.start}:"
                             f"{self.window.end} s; the recording spans {lo:.9g} to {hi:.9g} s")
        t = np.concatenate(self.times)
        self.times = []
        out = {}
        for target in self.targets:
            out[target] = np.concatenate(self.parts[target])
            self.parts[target] = []
        return t, out


def _check_reach(cols: dict[str, np.ndarray], chans: dict[str, ChannelInfo], first_row: int,
                 where: str) -> None:
    """Refuse a channel that reaches beyond :data:`_REACH` once converted (an infinity
    included: a scale that overflows)."""
    from ...quantities import SI
    from .channel_map import TARGETS

    for target, x in cols.items():
        with np.errstate(invalid="ignore"):
            beyond = np.abs(x) > _REACH[target]               # NaN runs are named later
        if beyond.any():
            k = int(np.argmax(beyond))
            unit = SI[TARGETS[target]]
            raise TraceError(f"{where}: channel {chans[target].label!r} ({target}) reaches "
                             f"{x[k]:.4g} {unit} at row {first_row + k:,}, beyond the "
                             f"{_REACH[target]:g} {unit} of any actuator's recording; check its "
                             "unit, scale and offset in the map (--inspect lists the units the "
                             "file declares)")


def _read(source, cmap: ChannelMap, chans: dict[str, ChannelInfo], conv: dict[str, Conversion],
          base: _TimeBase, window: Window, limit: int, where: str):
    order = [t for t in _ORDER if t in chans]
    n = _check_lengths(chans, base, where)
    first, stop = _rows(base, window, n)
    if n is not None and (stop if stop is not None else n) - first > limit:
        what = (f"{n:,} samples" if window == Window()
                else f"{(stop or n) - first:,} samples in the window")
        raise too_many_samples(where, f"the recording holds {what}", limit)
    signals = [t for t in order if t != "t"]
    span = ((base.start, base.start + (n - 1) / base.rate)
            if base.mode in ("rate", "own") and base.rate and n else None)
    collect = _Collector(signals, window, limit, where, span)
    for block in source.blocks([chans[t] for t in order], first, stop):
        with np.errstate(over="ignore", invalid="ignore"):     # refused below, not printed
            cols = {t: conv[t].apply(x) for t, x in zip(order, block.columns)}
        _check_reach(cols, chans, block.start, where)
        if base.mode == "channel":
            t = cols.pop("t")
        elif base.mode == "own" and block.t is not None:
            t = block.t
        else:
            t = base.start + (block.start + np.arange(block.n)) / base.rate
        collect.add(t, cols, block.start)
        if collect.done:
            break
    return collect.arrays()


def import_trace(path: str | Path, cmap: ChannelMap, *, window: Window = Window(),
                 max_samples: int = MAX_SAMPLES, map_name: str | None = None) -> Trace:
    """Read the bench export ``path`` through the channel map ``cmap`` into a validated
    trace (SI units, time from 0, the source and the map in its metadata); a
    :class:`~emaphm.traces.TraceError` says what stops it, naming the map as ``map_name``
    (default: the file it was loaded from, ``cmap.origin``)."""
    path = Path(path)
    map_name = map_name or cmap.origin
    with open_source(path, cmap.source) as source:
        info = source.info
        if info.damage:
            raise TraceError(f"{path}: {info.damage} (`emaphm import {path.name} --inspect` lists "
                             "what of it can be read)")
        chans = {spec.target: info.find(spec.name, spec.group, f"{map_name}: [channels] "
                                        f"{spec.target}") for spec in cmap.channels}
        _distinct(chans, map_name)
        for target, c in chans.items():
            if c.text is not None:
                raise TraceError(f"{map_name}: [channels] {target}: column {c.label!r} holds text, "
                                 f"not numbers (e.g. {c.text[:40]!r}); map a column of "
                                 "numbers" + (f"; {info.hint}" if info.hint else ""))
        conv = {spec.target: spec.conversion(chans[spec.target].unit,
                                             f"{map_name}: [channels] {spec.target}")
                for spec in cmap.channels}
        base = _time_base(cmap, info, chans, str(path))
        t, cols = _read(source, cmap, chans, conv, base, window, max_samples, str(path))
    return _trace(path, info, cmap, chans, t, cols, window, base)


def _trace(path: Path, info: SourceInfo, cmap: ChannelMap, chans: dict[str, ChannelInfo],
           t: np.ndarray, cols: dict[str, np.ndarray], window: Window, base: _TimeBase) -> Trace:
    where = str(path)
    for target, x in cols.items():
        _nan_runs(chans[target].label, target, x, t, where)
    _not_a_clock(cols["theta_m"], t, chans["theta_m"].label, where)
    if not np.all(np.isfinite(t)):
        _nan_runs(chans["t"].label if "t" in chans else "t", "t", t, t, where)
    cols, notes = derive_missing(cols, t)
    t0 = float(t[0])
    t = t - t0
    resampled = _uniform(t, where, t0)
    meta = {
        "source": {"file": path.name, "format": info.format, "sha256": file_digest(path),
                   "window": window.to_list(), "t_start": t0,
                   "time": _time_text(base, cmap, chans),
                   "channels": {k: v.label for k, v in chans.items()},
                   "map": cmap.to_dict()},
        "currents_measured": 3,
    }
    meta = derived_meta(meta, notes)
    if cmap.source.voltage_delay_periods is not None:
        meta["voltage_delay_periods"] = cmap.source.voltage_delay_periods
    if cmap.profile:
        from ...profiles import diagnostic

        meta["profile"] = diagnostic().to_dict()
    if resampled is not None:
        t_new = np.linspace(0.0, float(t[-1]), t.size)
        cols = {k: np.interp(t_new, t, v) for k, v in cols.items()}
        t = t_new
        meta["source"]["resampled"] = resampled
    trace = Trace(t=t, theta_ref=cols["theta_ref"], theta_m=cols["theta_m"],
                  omega_m=cols["omega_m"],
                  i_abc=np.column_stack([cols["i_a"], cols["i_b"], cols["i_c"]]),
                  torque=cols.get("torque"), meta=meta,
                  drive={name: cols[name] for name in DRIVE_COLUMNS if name in cols})
    warn_if_shorter_than_profile(trace, where)
    try:
        validate(trace)
    except TraceError as exc:
        raise TraceError(f"{where}: imported, but {exc}") from None
    return trace


def _not_a_clock(x: np.ndarray, t: np.ndarray, label: str, where: str) -> None:
    """Refuse a measured position that is the time base in s, ms, us or ns (read as rad or
    deg) to the rounding: a time column (the file's own, the time taken from [time] rate),
    which a diagnosis reads as a motion and finds healthy."""
    if x.size < 100:
        return
    step = (x[-1] - x[0]) / (x.size - 1)
    dt = (t[-1] - t[0]) / (t.size - 1)
    if step == 0 or not dt > 0 or np.max(np.abs(x - x[0] - step * np.arange(x.size))) > \
            1e-9 * np.max(np.abs(x)):
        return
    units = [f * u for f in (1, 1e3, 1e6, 1e9) for u in (1, np.pi / 180)]   # s..ns; rad, deg
    if any(abs(step / (dt * u) - 1) < 1e-6 for u in units):
        raise TraceError(f"{where}: channel {label!r} (theta_m) rises by {step:.4g} rad at every "
                         f"sample, {step / dt:g} times the time step: it is a time column, not a "
                         "measured position; map theta_m to the position the encoder measured "
                         "(`emaphm import FILE --inspect` lists the channels)")


def _time_text(base: _TimeBase, cmap: ChannelMap, chans: dict[str, ChannelInfo]) -> str:
    if base.mode == "channel":
        return f"channel {chans['t'].label}"
    if base.mode == "own":
        return f"master time base of the channel group of {chans[_first(chans)].label}"
    origin = "[time] rate of the map" if cmap.time.rate else "waveform rate of the channels"
    return f"{base.rate:g} Hz from {base.start:g} s ({origin})"


def _uniform(t: np.ndarray, where: str, t0: float = 0.0) -> str | None:
    """None for a uniform time base; a note when the steps scatter within
    :data:`_RESAMPLE_LIMIT` of their mean (the samples are then interpolated onto the
    uniform grid, with a warning); beyond it a TraceError at the step farthest from the
    median step (a gap, samples lost), in the recording's time (``t0`` + ``t``)."""
    if t.size < 3:
        return None
    steps = np.diff(t)
    dt = float(t[-1] - t[0]) / (t.size - 1)
    spread = float((steps.max() - steps.min()) / dt)
    if spread <= _UNIFORM_RTOL:
        return None
    if spread > _RESAMPLE_LIMIT:
        typical = float(np.median(steps))
        k = int(np.argmax(np.abs(steps - typical)))
        what = (f"a gap of {steps[k]:.6g} s (about {round(steps[k] / typical) - 1:,} samples "
                "missing)" if steps[k] > 1.5 * typical else f"a step of {steps[k]:.6g} s")
        raise TraceError(f"{where}: the time base has {what} between rows {k:,} and {k + 1:,} "
                         f"of the window (t = {t0 + t[k]:.9g} s to {t0 + t[k + 1]:.9g} s), where "
                         f"the other steps are about {typical:.6g} s; import a window before or "
                         "after it (--window START:END)")
    note = (f"time steps scattered by {spread:.3g} of the mean step {dt:.6g} s: interpolated "
            "onto the uniform grid")
    warnings.warn(TraceWarning(f"{where}: the {note}"), stacklevel=3)
    return note
