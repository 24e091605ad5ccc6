"""Physical measures and how they convert to SI: the one table emaphm reads units from.

A bench export writes its time in ms, its positions in degrees, its speed in rpm; a motor
catalogue gives inertias in kg cm^2 and back-EMF constants in V/krpm. :func:`measure`
parses such a text into a :class:`Measure` (what physical quantity it measures, and the
SI value of one of it), and :func:`quantity` parses a number with its measure
(``"1.1 kg cm^2"``). Nothing is guessed: a text not in the table is refused, with the
spellings the table knows for that quantity.

(The word "unit" is kept for a production unit, :mod:`emaphm.units`; here it is
"measure".)

==================  ==========  ===============================================
quantity            SI          measures read (besides the SI one)
==================  ==========  ===============================================
time                s           ms, us, ns, min, h
angle               rad         mrad, deg, rev (turn)
angular speed       rad/s       rpm (r/min, 1/min), krpm, deg/s, rev/s (rps)
current             A           mA, uA, kA
voltage             V           mV, kV
torque              N m         mN m, N mm, N cm
resistance          ohm         mohm, kohm
inductance          H           mH, uH
inertia             kg m^2      kg cm^2, kg mm^2, g cm^2
frequency           Hz          kHz, MHz
back-EMF constant   V s/rad     V/krpm, V/rpm, mV/rpm, V/(rad/s)
torque constant     N m/A       mN m/A
power               W           kW
==================  ==========  ===============================================
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal

__all__ = ["Measure", "QuantityError", "SI", "measure", "quantity", "split", "known_spellings",
           "scale_ratio"]


class QuantityError(ValueError):
    """A measure that is not in the table, or that does not fit the quantity asked for."""


#: The SI measure of each quantity.
SI: dict[str, str] = {
    "time": "s", "angle": "rad", "angular speed": "rad/s", "current": "A", "voltage": "V",
    "torque": "N m", "resistance": "ohm", "inductance": "H", "inertia": "kg m^2",
    "frequency": "Hz", "back-EMF constant": "V s/rad", "torque constant": "N m/A",
    "power": "W", "dimensionless": "1",
}


@dataclass(frozen=True)
class Measure:
    """One measure of a quantity: ``1 symbol = factor SI``.

    ``how`` writes the factor as a person would multiply by it (``"pi/180"``,
    ``"0.001 (divide by 1000)"``).
    """

    symbol: str
    kind: str
    factor: float
    how: str

    @property
    def si(self) -> str:
        """The SI measure of the same quantity (``"rad"`` for degrees)."""
        return SI[self.kind]

    @property
    def is_si(self) -> bool:
        return self.factor == 1.0

    def to_si(self, value):
        """``value`` (a number or an array) in this measure, expressed in SI."""
        return value * self.factor if self.factor != 1.0 else value

    def number_to_si(self, number: float | str) -> float:
        """One number (or its text) in SI; a decimal factor (ms, kg cm^2) is applied in
        decimal, so that ``7.7 kg cm^2`` is the double nearest 7.7e-4, as if typed."""
        if self.factor == 1.0:
            return float(number)
        exact = Decimal(repr(self.factor))
        if len(exact.as_tuple().digits) == 1:          # 1e-3, 1e-4, 1000: a power of ten
            return float(Decimal(number if isinstance(number, str) else repr(float(number)))
                         * exact)
        return float(number) * self.factor


_RPM = 2.0 * math.pi / 60.0
_TABLE: list[tuple[str, tuple[str, ...], float, str]] = [
    # kind, spellings (the first is how emaphm writes it), factor to SI, the factor as text
    ("time", ("s", "sec", "second", "seconds"), 1.0, "1"),
    ("time", ("ms", "msec", "millisecond", "milliseconds"), 1e-3, "0.001 (divide by 1000)"),
    ("time", ("us", "\u00b5s", "\u03bcs", "usec", "microsecond", "microseconds"), 1e-6, "1e-6"),
    ("time", ("ns",), 1e-9, "1e-9"),
    ("time", ("min", "minute", "minutes"), 60.0, "60"),
    ("time", ("h", "hour", "hours"), 3600.0, "3600"),
    ("angle", ("rad", "radian", "radians"), 1.0, "1"),
    ("angle", ("mrad",), 1e-3, "0.001 (divide by 1000)"),
    ("angle", ("deg", "degree", "degrees", "\u00b0"), math.pi / 180.0, "pi/180"),
    ("angle", ("rev", "revs", "revolution", "revolutions", "turn", "turns"), 2 * math.pi, "2*pi"),
    ("angular speed", ("rad/s", "rad/sec", "rad s^-1", "rad s-1", "rad/second"), 1.0, "1"),
    ("angular speed", ("rpm", "r/min", "rev/min", "1/min", "min^-1", "U/min"), _RPM, "2*pi/60"),
    ("angular speed", ("krpm",), 1000.0 * _RPM, "2*pi/60*1000"),
    ("angular speed", ("deg/s", "\u00b0/s", "degree/s", "degrees/s"), math.pi / 180.0, "pi/180"),
    ("angular speed", ("rev/s", "rps", "r/s", "Hz(mech)"), 2 * math.pi, "2*pi"),
    ("current", ("A", "amp", "amps", "ampere", "amperes"), 1.0, "1"),
    ("current", ("mA",), 1e-3, "0.001 (divide by 1000)"),
    ("current", ("uA", "\u00b5A", "\u03bcA"), 1e-6, "1e-6"),
    ("current", ("kA",), 1e3, "1000"),
    ("voltage", ("V", "volt", "volts"), 1.0, "1"),
    ("voltage", ("mV",), 1e-3, "0.001 (divide by 1000)"),
    ("voltage", ("kV",), 1e3, "1000"),
    ("torque", ("N m", "Nm", "N-m", "newton metre", "newton meter"), 1.0, "1"),
    ("torque", ("mN m", "mNm"), 1e-3, "0.001 (divide by 1000)"),
    ("torque", ("N mm", "Nmm"), 1e-3, "0.001 (divide by 1000)"),
    ("torque", ("N cm", "Ncm"), 1e-2, "0.01 (divide by 100)"),
    ("resistance", ("ohm", "ohms", "\u03a9", "\u2126"), 1.0, "1"),
    ("resistance", ("mohm", "m\u03a9", "m\u2126", "milliohm"), 1e-3, "0.001 (divide by 1000)"),
    ("resistance", ("kohm", "k\u03a9", "k\u2126"), 1e3, "1000"),
    ("inductance", ("H", "henry"), 1.0, "1"),
    ("inductance", ("mH",), 1e-3, "0.001 (divide by 1000)"),
    ("inductance", ("uH", "\u00b5H", "\u03bcH"), 1e-6, "1e-6"),
    ("inertia", ("kg m^2", "kg m2", "kgm^2", "kgm2"), 1.0, "1"),
    ("inertia", ("kg cm^2", "kg cm2", "kgcm^2", "kgcm2"), 1e-4, "1e-4"),
    ("inertia", ("kg mm^2", "kg mm2", "kgmm^2", "kgmm2"), 1e-6, "1e-6"),
    ("inertia", ("g cm^2", "g cm2", "gcm^2", "gcm2"), 1e-7, "1e-7"),
    ("frequency", ("Hz",), 1.0, "1"),
    ("frequency", ("kHz",), 1e3, "1000"),
    ("frequency", ("MHz",), 1e6, "1e6"),
    ("back-EMF constant", ("V s/rad", "Vs/rad", "V/(rad/s)"), 1.0, "1"),
    ("back-EMF constant", ("V/krpm", "V/1000rpm", "V/1000 rpm", "mV/rpm", "mV/min^-1",
                           "V/1000min^-1"), 1.0 / (1000.0 * _RPM), "60/(2*pi*1000)"),
    ("back-EMF constant", ("V/rpm",), 1.0 / _RPM, "60/(2*pi)"),
    ("torque constant", ("N m/A", "Nm/A"), 1.0, "1"),
    ("torque constant", ("mN m/A", "mNm/A"), 1e-3, "0.001 (divide by 1000)"),
    ("power", ("W", "watt", "watts"), 1.0, "1"),
    ("power", ("kW",), 1e3, "1000"),
    ("dimensionless", ("1", "-", ""), 1.0, "1"),
]


def _key(text: str) -> str:
    """A spelling as looked up: brackets, spaces and multiplication dots dropped,
    superscripts written with ``^``."""
    t = text.strip()
    if len(t) >= 2 and t[0] + t[-1] in ("[]", "()", "{}"):
        t = t[1:-1].strip()
    t = (t.replace("\u00b2", "^2").replace("\u207b\u00b9", "^-1").replace("\u00b7", "")
         .replace("*", "").replace(".", "") if not re.fullmatch(r"[\d.]+", t) else t)
    return re.sub(r"\s+", "", t)


_EXACT: dict[str, Measure] = {}
_FOLDED: dict[str, Measure | None] = {}
for _kind, _spellings, _factor, _how in _TABLE:
    _m = Measure(_spellings[0], _kind, _factor, _how)
    for _s in _spellings:
        _EXACT[_key(_s)] = _m
for _k, _m in _EXACT.items():
    _f = _k.lower()
    # a case-insensitive spelling counts only where it names one measure (MS is not ms)
    _FOLDED[_f] = _m if _FOLDED.get(_f, _m) == _m else None


def known_spellings(kind: str) -> list[str]:
    """The measures of ``kind`` the table reads, as emaphm writes them."""
    return [s[0] for k, s, _, _ in _TABLE if k == kind]


def measure(text: str, kind: str | None = None, *, where: str = "") -> Measure:
    """The :class:`Measure` ``text`` names (``"ms"``, ``"[deg]"``, ``"kg cm^2"``).

    With ``kind``, the measure must be of that quantity. A :class:`QuantityError`
    (prefixed by ``where``) names what was not understood and the known spellings.
    """
    prefix = f"{where}: " if where else ""
    if not isinstance(text, str):
        raise QuantityError(f"{prefix}a unit must be text such as 'ms' or 'deg', got {text!r}")
    key = _key(text)
    found = _EXACT.get(key) or _FOLDED.get(key.lower())
    if found is None:
        known = ", ".join(known_spellings(kind)) if kind else "see emaphm.quantities"
        what = f" for a {kind}" if kind else ""
        raise QuantityError(f"{prefix}unknown unit {text.strip()[:40]!r}{what}; known: {known}")
    if kind is not None and found.kind != kind:
        raise QuantityError(
            f"{prefix}'{text.strip()[:40]}' is a unit of {found.kind} ({found.si}), not of "
            f"{kind} ({SI[kind]}); known units of {kind}: {', '.join(known_spellings(kind))}")
    return found


_NUMBER = re.compile(r"\s*([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


def split(value: float | int | str, kind: str, *, where: str = "") -> tuple[float, Measure | None]:
    """A number with its measure as written: ``"40 V/krpm"`` -> ``(40.0, V/krpm)``; a bare
    number -> ``(value, None)``."""
    prefix = f"{where}: " if where else ""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value), None
    m = _NUMBER.fullmatch(value) if isinstance(value, str) else None
    if not m:
        raise QuantityError(f"{prefix}expected a number with its unit, e.g. '1.1 {SI[kind]}', "
                            f"got {str(value).strip()[:40]!r}")
    return float(m.group(1)), (measure(m.group(2), kind, where=where) if m.group(2) else None)


def quantity(value: float | int | str, kind: str, *, where: str = "",
             default: str | None = None) -> float:
    """The SI value of ``value``: a text with a number and a measure (``"1.1 kg cm^2"``,
    ``"40 V/krpm"``), or a bare number, taken in ``default`` (a spelling of ``kind``;
    without one a bare number is taken as SI)."""
    prefix = f"{where}: " if where else ""
    if isinstance(value, bool):
        raise QuantityError(f"{prefix}expected a number with its unit, e.g. '1.1 {SI[kind]}', "
                            f"got {value!r}")
    if isinstance(value, (int, float)):
        v = float(value)
        unit = measure(default, kind, where=where) if default is not None else None
    elif isinstance(value, str):
        m = _NUMBER.fullmatch(value)
        if not m:
            raise QuantityError(f"{prefix}expected a number with its unit, e.g. '1.1 "
                                f"{default or SI[kind]}', got {value.strip()[:40]!r}")
        v = m.group(1)
        text = m.group(2) or default
        unit = measure(text, kind, where=where) if text is not None else None
    else:
        raise QuantityError(f"{prefix}expected a number with its unit, e.g. '1.1 {SI[kind]}', "
                            f"got {type(value).__name__}")
    if not math.isfinite(float(v)):
        raise QuantityError(f"{prefix}expected a finite number, got {value!r}")
    return unit.number_to_si(v) if unit is not None else float(v)


def scale_ratio(text: str, recorded: str, wanted: str, *, where: str = "") -> float:
    """The factor that turns a channel recorded in ``recorded`` (a quantity) into
    ``wanted``, read from a ratio such as ``"10 A/V"`` (wanted per recorded: multiply)
    or ``"100 mV/A"`` (recorded per wanted, a probe's sensitivity: divide)."""
    prefix = f"{where}: " if where else ""
    m = _NUMBER.fullmatch(text) if isinstance(text, str) else None
    parts = m.group(2).split("/") if m else []
    if not m or len(parts) != 2:
        raise QuantityError(f"{prefix}expected a ratio such as '10 A/V' or '100 mV/A', got "
                            f"{str(text).strip()[:40]!r}")
    value = float(m.group(1))
    top, bottom = (measure(p, where=where) for p in parts)
    if value == 0 or not math.isfinite(value):
        raise QuantityError(f"{prefix}the ratio {text.strip()[:40]!r} must be finite and not 0")
    if (top.kind, bottom.kind) == (wanted, recorded):
        return value * top.factor / bottom.factor
    if (top.kind, bottom.kind) == (recorded, wanted):
        return bottom.factor / (value * top.factor)
    raise QuantityError(f"{prefix}the ratio {text.strip()[:40]!r} is {top.kind} per "
                        f"{bottom.kind}; a channel recorded as {recorded} needs {wanted} per "
                        f"{recorded} (e.g. '10 {SI[wanted]}/{SI[recorded]}') or its sensitivity "
                        f"({recorded} per {wanted})")
