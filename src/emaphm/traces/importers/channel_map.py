"""The channel map: which channel of a bench export is which emaphm column, in what unit,
scaled how; where the time comes from. A TOML file, the contract of ``emaphm import``
(documented with examples in ``docs/bench-import.md``)::

    [source]                 # optional: how to read the file
    delimiter = ";"          # CSV: "," ";" "\\t" (judged from the file if left out)
    decimal = ","            # CSV: "." or "," (judged from the file if left out)
    group = "Measurement"    # TDMS group, MDF channel group name, MATLAB struct: default

    [time]                   # without a t channel (or where the file has no time base)
    rate = "20 kHz"          # sample rate: Hz, or a number with its unit
    start = 0.0              # s, time of the first sample

    [channels]
    t = { name = "Zeit", unit = "ms" }
    theta_ref = { name = "Soll", unit = "deg" }
    theta_m = { name = "Ist", unit = "deg" }
    omega_m = { name = "n", unit = "rpm" }            # optional: derived from theta_m
    i_a = { name = "CH1", unit = "V", scale = "100 mV/A", offset = 0.0 }
    i_b = { name = "I_V", unit = "A" }
    # i_c left out: -(i_a + i_b), and the trace says only two currents were measured

    [profile]                # optional: the test the recording holds
    name = "diagnostic"

A channel's value is ``scale * recorded + offset`` in its ``unit``, then converted to SI.
A current recorded in volts (a probe) takes ``scale`` as amperes per volt (a number, or a
ratio such as ``"10 A/V"``, or the probe's sensitivity ``"100 mV/A"``), and ``offset`` in
amperes. A channel without ``unit`` takes the unit the file declares for it; where the
file declares none, the map must give one: units are read, never guessed.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ...quantities import SI, QuantityError, measure, quantity, scale_ratio
from ..container import TraceError

__all__ = ["TARGETS", "REQUIRED", "MapError", "ChannelSpec", "TimeSpec", "SourceOptions",
           "ChannelMap", "Conversion", "load_map", "PROFILES"]

#: The emaphm columns a map may fill, with the quantity each measures.
TARGETS: dict[str, str] = {"t": "time", "theta_ref": "angle", "theta_m": "angle",
                           "omega_m": "angular speed", "i_a": "current", "i_b": "current",
                           "i_c": "current", "torque": "torque",
                           # what the drive logs (emaphm.traces.container.DRIVE_COLUMNS)
                           **{f"v_{x}": "voltage" for x in "abcdq"},
                           **{f"d_{x}": "dimensionless" for x in "abc"}, "v_dc": "voltage",
                           "i_d_ref": "current", "i_q_ref": "current",
                           "omega_ref": "angular speed"}
#: Columns every map needs (t, omega_m and i_c can be derived or given by [time]).
REQUIRED: tuple[str, ...] = ("theta_ref", "theta_m", "i_a", "i_b")
#: Test profiles a map can name in ``[profile] name``.
PROFILES: tuple[str, ...] = ("diagnostic",)
_CHANNEL_FIELDS = ("name", "group", "unit", "scale", "offset")
_SOURCE_FIELDS = ("format", "delimiter", "decimal", "encoding", "group", "voltage_delay_periods")
_FORMATS = ("csv", "parquet", "mat", "tdms", "mf4")


#: The slowest sample rate a map may give (a test profile lasts half a second), the
#: largest start time (a Unix time of the year 2286), and the span of a channel's scale
#: (as a number) and offset (in its unit): beyond them no recording is meant.
MIN_RATE = 1.0
MAX_START = 1e10
SCALE_SPAN = (1e-9, 1e9)
MAX_OFFSET = 1e6


class MapError(TraceError):
    """A channel map that cannot be used: the message names the table, the field and the
    fix."""


@dataclass(frozen=True)
class Conversion:
    """``SI = gain * recorded + bias``: a channel's scale, offset and unit folded into one
    affine map; ``unit`` is the recorded unit it was made from."""

    gain: float
    bias: float
    unit: str

    def apply(self, x):
        if self.gain == 1.0 and self.bias == 0.0:
            return x
        return x * self.gain + self.bias if self.bias else x * self.gain


@dataclass(frozen=True)
class ChannelSpec:
    """One ``[channels]`` entry: the source channel (``name``, ``group``) that fills the
    emaphm column ``target``, its ``unit`` (None: the file's own) and ``scale``/``offset``
    (a number, or for a probe a ratio text such as ``"10 A/V"``)."""

    target: str
    name: str
    group: str | None = None
    unit: str | None = None
    scale: float | str = 1.0
    offset: float = 0.0

    def conversion(self, declared: str | None, where: str) -> Conversion:
        """The SI conversion of this channel, its unit being the map's or else
        ``declared`` (the file's). Where both are units of the table and differ, a
        :class:`MapError` names both (a file's unit the table lacks yields to the map's)."""
        kind = TARGETS[self.target]
        if declared is not None and not declared.strip():
            declared = None
        unit = self.unit if self.unit is not None else declared
        if unit is None or not unit.strip():
            raise MapError(f"{where}: channel {self.name!r} has no unit in the map and the file "
                           f"declares none; add unit = \"{SI[kind]}\" (or the unit it was "
                           f"recorded in: {', '.join(_spellings(kind))})")
        try:
            m = measure(unit)
        except QuantityError:
            by = (f"the file declares unit {unit.strip()[:40]!r} for channel {self.name!r}, "
                  f"not one emaphm knows; give its unit in the map, unit = \"...\""
                  if self.unit is None else f"unknown unit {unit.strip()[:40]!r}")
            raise MapError(f"{where}: {by}; known units of {kind}: "
                           f"{', '.join(_spellings(kind))}") from None
        if self.unit is not None and declared is not None:
            self._agree(m, declared, where)
        if m.kind == kind:
            if isinstance(self.scale, str):
                raise MapError(f"{where}: scale {self.scale!r} is a ratio, but {self.target} is "
                               f"recorded in {m.symbol}, a unit of {kind}: give scale as a number")
            return Conversion(m.factor * float(self.scale), m.factor * self.offset, unit)
        if kind == "current" and m.kind == "voltage":
            if isinstance(self.scale, str):
                try:
                    ratio = scale_ratio(self.scale, "voltage", "current", where=where)
                except QuantityError as exc:
                    raise MapError(str(exc)) from None
            elif self.scale == 1.0:
                raise MapError(f"{where}: {self.target} is recorded in {m.symbol} (a probe): give "
                               "the probe's scale, e.g. scale = \"10 A/V\" or its sensitivity "
                               "scale = \"100 mV/A\"")
            else:
                ratio = float(self.scale)
            return Conversion(m.factor * ratio, float(self.offset), unit)
        raise MapError(f"{where}: unit {unit!r} is a unit of {m.kind}, which does not convert to "
                       f"the {kind} of {self.target} ({SI[kind]}); known units of {kind}: "
                       f"{', '.join(_spellings(kind))}"
                       + (" (or V with a probe's scale)" if kind == "current" else ""))

    def _agree(self, m, declared: str, where: str) -> None:
        """Refuse a map's unit that contradicts the file's, both of one quantity (a current
        declared in A read as mA is 1000 times off, silently); a file's unit of another
        quantity is the sensor's output (a potentiometer's V), which the map's unit and
        scale convert."""
        try:
            f = measure(declared)
        except QuantityError:
            return
        if f == m or f.kind != m.kind:   # another quantity: a sensor's output (V) read
            return                       # through the map's unit and scale, as intended
        fix = f"remove unit from the map to read it in {declared.strip()}"
        if not isinstance(self.scale, str) and not self.offset:
            fix += (f", or, where the file's unit is wrong, remove unit and give "
                    f"scale = {float(self.scale) * m.factor / f.factor:.10g} (its values in "
                    f"{self.unit.strip()})")
        raise MapError(f"{where}: channel {self.name!r} is declared in {declared.strip()!r} by "
                       f"the file, in {self.unit.strip()!r} by the map; {fix}")

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"name": self.name}
        if self.group is not None:
            d["group"] = self.group
        if self.unit is not None:
            d["unit"] = self.unit
        if self.scale != 1.0:
            d["scale"] = self.scale
        if self.offset != 0.0:
            d["offset"] = self.offset
        return d


def _spellings(kind: str) -> list[str]:
    from ...quantities import known_spellings

    return known_spellings(kind)


@dataclass(frozen=True)
class TimeSpec:
    """``[time]``: the sample ``rate`` [Hz] of a file without a time channel and the time
    ``start`` [s] of its first sample."""

    rate: float | None = None
    start: float = 0.0


@dataclass(frozen=True)
class SourceOptions:
    """``[source]``: how to read the file where its suffix and content do not say."""

    format: str | None = None
    delimiter: str | None = None
    decimal: str | None = None
    encoding: str | None = None
    group: str | None = None
    #: whether a logged voltage command was applied in the period it was logged in (0) or
    #: in the next (1): the imported trace's metadata ``voltage_delay_periods``
    voltage_delay_periods: int | None = None


@dataclass(frozen=True)
class ChannelMap:
    """A parsed channel map (see the module docstring); build it with :func:`load_map` or
    :meth:`from_dict`."""

    channels: tuple[ChannelSpec, ...]
    time: TimeSpec = field(default_factory=TimeSpec)
    source: SourceOptions = field(default_factory=SourceOptions)
    profile: str | None = None
    #: where the map came from (its file), as refusals name it
    origin: str = field(default="map", compare=False)

    def channel(self, target: str) -> ChannelSpec | None:
        return next((c for c in self.channels if c.target == target), None)

    @property
    def targets(self) -> tuple[str, ...]:
        return tuple(c.target for c in self.channels)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (for a trace's metadata)."""
        d: dict[str, Any] = {"channels": {c.target: c.to_dict() for c in self.channels}}
        if self.time != TimeSpec():
            d["time"] = {k: v for k, v in (("rate", self.time.rate), ("start", self.time.start))
                         if v is not None}
        src = {k: getattr(self.source, k) for k in _SOURCE_FIELDS
               if getattr(self.source, k) is not None and getattr(self.source, k) != ""}
        if src:
            d["source"] = src
        if self.profile:
            d["profile"] = {"name": self.profile}
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "map") -> "ChannelMap":
        """Parse a map from its TOML table; :class:`MapError` names what is wrong and where."""
        if not isinstance(data, Mapping):
            raise MapError(f"{source}: expected a table with [channels], got {type(data).__name__}")
        unknown = sorted(set(data) - {"channels", "time", "source", "profile"})
        if unknown:
            raise MapError(f"{source}: unknown table(s) {unknown}; a map has [channels], [time], "
                           "[source] and [profile]")
        src = _source_options(_table(data, "source", source), source)
        chans = _channels(_table(data, "channels", source, required=True), src, source)
        time = _time(_table(data, "time", source), source)
        targets = {c.target for c in chans}
        if "t" in targets and time.rate is not None:
            raise MapError(f"{source}: give either a t channel in [channels] or [time] rate, not "
                           "both")
        missing = [t for t in REQUIRED if t not in targets]
        if missing:
            raise MapError(f"{source}: [channels] is missing {', '.join(missing)}; every map needs "
                           f"{', '.join(REQUIRED)} (t, omega_m and i_c can be left out: t from "
                           "[time] rate or the file's time base, omega_m derived from theta_m, "
                           "i_c = -(i_a + i_b))")
        prof = _table(data, "profile", source)
        name = prof.get("name") if prof else None
        if prof and (set(prof) - {"name"} or name not in PROFILES):
            raise MapError(f"{source}: [profile] takes name = one of {', '.join(PROFILES)}, got "
                           f"{dict(prof)!r:.80}")
        return cls(channels=chans, time=time, source=src, profile=name, origin=source)


def _table(data: Mapping[str, Any], key: str, source: str, required: bool = False) -> dict:
    value = data.get(key)
    if value is None:
        if required:
            raise MapError(f"{source}: no [{key}] table; map each emaphm column to a channel of "
                           "the file, e.g. [channels] i_a = { name = \"I_U\", unit = \"A\" }")
        return {}
    if not isinstance(value, Mapping):
        raise MapError(f"{source}: {key} must be a table [{key}], got {value!r:.60}")
    return dict(value)


def _text(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise MapError(f"{where}: expected a non-empty text, got {value!r:.60}")
    return value


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(float(value)):
        raise MapError(f"{where}: expected a finite number, got {value!r:.60}")
    return float(value)


def _source_options(t: dict, source: str) -> SourceOptions:
    extra = sorted(set(t) - set(_SOURCE_FIELDS))
    if extra:
        raise MapError(f"{source}: unknown field(s) {extra} in [source]; known: "
                       f"{', '.join(_SOURCE_FIELDS)}")
    kw = {k: _text(v, f"{source}: [source] {k}") if k not in ("delimiter", "voltage_delay_periods")
          else v for k, v in t.items()}
    delay = kw.get("voltage_delay_periods")
    if delay is not None and (isinstance(delay, bool) or delay not in (0, 1)):
        raise MapError(f"{source}: [source] voltage_delay_periods = {delay!r:.20}: give 0 (a logged "
                       "voltage command applies in the period it was logged in) or 1 (in the next)")
    if "delimiter" in kw:
        d = kw["delimiter"]
        d = "\t" if d in ("\\t", "tab") else d
        if d not in (",", ";", "\t", " ", "|"):
            raise MapError(f"{source}: [source] delimiter {d!r:.20} is not one of ',' ';' '\\t' "
                           "' ' '|'")
        kw["delimiter"] = d
    if kw.get("decimal") not in (None, ".", ","):
        raise MapError(f"{source}: [source] decimal must be \".\" or \",\", got {kw['decimal']!r:.20}")
    if kw.get("format") is not None and kw["format"].lower() not in _FORMATS:
        raise MapError(f"{source}: [source] format {kw['format']!r:.20} is not one of "
                       f"{', '.join(_FORMATS)}")
    if kw.get("format"):
        kw["format"] = kw["format"].lower()
    return SourceOptions(**kw)


def _channels(t: dict, src: SourceOptions, source: str) -> tuple[ChannelSpec, ...]:
    out = []
    for target, spec in t.items():
        where = f"{source}: [channels] {target}"
        if target not in TARGETS:
            raise MapError(f"{source}: [channels] has {target!r:.40}, not an emaphm column; the "
                           f"columns are {', '.join(TARGETS)}")
        if isinstance(spec, str):
            spec = {"name": spec}
        if not isinstance(spec, Mapping):
            raise MapError(f"{where}: expected {{ name = \"...\", unit = \"...\" }}, got "
                           f"{spec!r:.60}")
        extra = sorted(set(spec) - set(_CHANNEL_FIELDS))
        if extra:
            raise MapError(f"{where}: unknown field(s) {extra}; a channel has "
                           f"{', '.join(_CHANNEL_FIELDS)}")
        if "name" not in spec:
            raise MapError(f"{where}: no name; give the channel's name in the file, "
                           "name = \"...\"")
        scale = spec.get("scale", 1.0)
        if not isinstance(scale, str):
            scale = _number(scale, f"{where}.scale")
            if scale == 0.0:
                raise MapError(f"{where}.scale: must not be 0")
            if not SCALE_SPAN[0] <= abs(scale) <= SCALE_SPAN[1]:
                raise MapError(f"{where}.scale = {scale:g} is beyond {SCALE_SPAN[0]:g} to "
                               f"{SCALE_SPAN[1]:g}; give the factor from the recorded value to "
                               "the channel's unit (a unit prefix goes in unit = \"...\")")
        offset = _number(spec.get("offset", 0.0), f"{where}.offset")
        if abs(offset) > MAX_OFFSET:
            raise MapError(f"{where}.offset = {offset:g} is beyond +-{MAX_OFFSET:g} in the "
                           "channel's unit; give the recorded zero of the channel")
        group = spec.get("group", src.group)
        out.append(ChannelSpec(
            target=target, name=_text(spec["name"], f"{where}.name"),
            group=_text(group, f"{where}.group") if group is not None else None,
            unit=_text(spec["unit"], f"{where}.unit") if "unit" in spec else None,
            scale=scale, offset=offset))
    # each conversion is checked once here where the map gives the unit; a unit the file
    # declares is checked when the file is read
    for c in out:
        if c.unit is not None:
            c.conversion(None, f"{source}: [channels] {c.target}")
    return tuple(out)


def _time(t: dict, source: str) -> TimeSpec:
    extra = sorted(set(t) - {"rate", "start"})
    if extra:
        raise MapError(f"{source}: unknown field(s) {extra} in [time]; known: rate (Hz), "
                       "start (s)")
    try:
        rate = (quantity(t["rate"], "frequency", where=f"{source}: [time] rate", default="Hz")
                if "rate" in t else None)
        start = quantity(t.get("start", 0.0), "time", where=f"{source}: [time] start", default="s")
    except QuantityError as exc:
        raise MapError(str(exc)) from None
    if rate is not None and not (MIN_RATE <= rate <= 10e6):
        raise MapError(f"{source}: [time] rate = {rate:g} Hz is outside {MIN_RATE:g} Hz to 10 MHz; "
                       "give the sample rate in Hz, e.g. rate = 20000 or rate = \"20 kHz\"")
    if not abs(start) <= MAX_START:
        raise MapError(f"{source}: [time] start = {start:g} s is beyond {MAX_START:g} s (a clock "
                       "time of the year 2286); give the time of the first sample in seconds, "
                       "e.g. start = 0")
    return TimeSpec(rate=rate, start=start)


def load_map(path: str | os.PathLike[str]) -> ChannelMap:
    """Read a channel map from a TOML file (:class:`MapError` naming the file and the
    problem)."""
    from ...params import read_toml

    return ChannelMap.from_dict(read_toml(path, "channel map", MapError), source=str(path))
