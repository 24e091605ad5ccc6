"""Position command and load torque profiles.

A :class:`Profile` is data: a duration and two sums of elementary shapes (one
for the position command ``theta_ref`` [rad], one for the external load
torque ``T_l`` [N m]). Shapes are small frozen dataclasses evaluated on a
NumPy time grid, so a profile can be stored in trace metadata and rebuilt.

The default :func:`diagnostic` profile is designed so that every fault of the
vector ``k`` leaves a mark in the phase currents (see its docstring). The built-in
profiles (:data:`PROFILES`, :func:`get_profile`) and a user's own command read from a
CSV file (:func:`read_profile`) are what ``emaphm simulate --profile`` takes.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, asdict, dataclass, field, fields
from typing import Any, Union

import numpy as np

from ._text import shown

__all__ = ["Step", "Ramp", "Sine", "Chirp", "Trapezoid", "Constant", "Tabulated", "Profile",
           "ProfileError", "diagnostic", "step", "ramp", "sine", "chirp", "trapezoid", "PROFILES",
           "get_profile", "read_profile"]


class ProfileError(ValueError):
    """A profile or one of its shapes is ill-defined."""


def _finite(owner: str, **values: float) -> None:
    for name, v in values.items():
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise ProfileError(f"{owner}.{name} must be a number, got {shown(v)}")
        if not math.isfinite(v):
            raise ProfileError(f"{owner}.{name} must be finite, got {v!r}")


@dataclass(frozen=True)
class Step:
    """``height`` [rad or N m] from time ``t0`` [s] on."""

    t0: float
    height: float

    def __post_init__(self) -> None:
        _finite("Step", t0=self.t0, height=self.height)

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return np.where(t >= self.t0, self.height, 0.0)


@dataclass(frozen=True)
class Ramp:
    """Linear change by ``height`` between ``t0`` and ``t1`` [s], held afterwards."""

    t0: float
    t1: float
    height: float

    def __post_init__(self) -> None:
        _finite("Ramp", t0=self.t0, t1=self.t1, height=self.height)
        if not self.t1 > self.t0:
            raise ProfileError(f"Ramp needs t1 > t0, got t0={self.t0}, t1={self.t1}")

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return self.height * np.clip((t - self.t0) / (self.t1 - self.t0), 0.0, 1.0)


@dataclass(frozen=True)
class Sine:
    """``amplitude * sin(2 pi f (t - t0))`` on ``[t0, t1)``, zero elsewhere."""

    amplitude: float
    frequency: float
    t0: float = 0.0
    t1: float = math.inf

    def __post_init__(self) -> None:
        _finite("Sine", amplitude=self.amplitude, frequency=self.frequency, t0=self.t0)
        if self.frequency <= 0 or not self.t1 > self.t0:
            raise ProfileError("Sine needs frequency > 0 [Hz] and t1 > t0")

    def __call__(self, t: np.ndarray) -> np.ndarray:
        on = (t >= self.t0) & (t < self.t1)
        return np.where(on, self.amplitude * np.sin(2 * np.pi * self.frequency * (t - self.t0)), 0.0)


@dataclass(frozen=True)
class Chirp:
    """A linear frequency sweep ``amplitude * sin(2 pi (f0 tau + (f1 - f0) tau^2 / (2 T)))``,
    ``tau = t - t0``, ``T = t1 - t0``, on ``[t0, t1)``, zero elsewhere: the frequency
    [Hz] rises (or falls) linearly from ``f0`` at ``t0`` to ``f1`` at ``t1``."""

    amplitude: float
    f0: float
    f1: float
    t0: float
    t1: float

    def __post_init__(self) -> None:
        _finite("Chirp", amplitude=self.amplitude, f0=self.f0, f1=self.f1, t0=self.t0, t1=self.t1)
        if self.f0 <= 0 or self.f1 <= 0 or not self.t1 > self.t0:
            raise ProfileError("Chirp needs f0 > 0 and f1 > 0 [Hz] and a finite t1 > t0 [s]")

    def __call__(self, t: np.ndarray) -> np.ndarray:
        tau = t - self.t0
        rate = (self.f1 - self.f0) / (self.t1 - self.t0)
        on = (t >= self.t0) & (t < self.t1)
        return np.where(on, self.amplitude * np.sin(2 * np.pi * (self.f0 * tau + 0.5 * rate * tau ** 2)),
                        0.0)


@dataclass(frozen=True)
class Trapezoid:
    """A move by ``height`` starting at ``t0`` with a trapezoidal speed profile.

    Speed limited to ``v_max`` [rad/s], acceleration to ``a_max`` [rad/s^2]
    (a triangular profile when the move is too short to reach ``v_max``).
    """

    t0: float
    height: float
    v_max: float
    a_max: float

    def __post_init__(self) -> None:
        _finite("Trapezoid", t0=self.t0, height=self.height, v_max=self.v_max, a_max=self.a_max)
        if self.v_max <= 0 or self.a_max <= 0:
            raise ProfileError("Trapezoid needs v_max > 0 [rad/s] and a_max > 0 [rad/s^2]")

    def __call__(self, t: np.ndarray) -> np.ndarray:
        d = abs(self.height)
        v = min(self.v_max, math.sqrt(d * self.a_max))
        ta = v / self.a_max                     # acceleration time
        tc = max(d / v - ta, 0.0)               # cruise time (rounding can make it -0)
        tau = np.clip(t - self.t0, 0.0, 2 * ta + tc)
        acc = 0.5 * self.a_max * np.minimum(tau, ta) ** 2
        cruise = v * np.clip(tau - ta, 0.0, tc)
        tdec = np.clip(tau - ta - tc, 0.0, ta)
        dec = v * tdec - 0.5 * self.a_max * tdec ** 2
        return math.copysign(1.0, self.height) * (acc + cruise + dec)


@dataclass(frozen=True)
class Constant:
    """A constant value (a steady load torque, an offset)."""

    value: float

    def __post_init__(self) -> None:
        _finite("Constant", value=self.value)

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return np.full(np.shape(t), self.value)


@dataclass(frozen=True)
class Tabulated:
    """Samples ``values`` at times ``t`` [s], linearly interpolated, held at the ends.

    Replays a recorded command (a measured trace's ``theta_ref``).
    """

    t: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        v = np.asarray(self.values, dtype=float)
        if t.ndim != 1 or t.shape != v.shape or t.size < 2:
            raise ProfileError("Tabulated needs two 1-D sequences t and values of the same length >= 2")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v)) and np.all(np.diff(t) > 0)):
            raise ProfileError("Tabulated needs finite values and strictly increasing times")
        object.__setattr__(self, "t", tuple(t.tolist()))
        object.__setattr__(self, "values", tuple(v.tolist()))
        # the same samples as arrays, for np.interp (not fields: equality, hashing and
        # to_dict see the tuples); converting the tuples on every call cost more than
        # the interpolation
        t.flags.writeable = False
        v.flags.writeable = False
        object.__setattr__(self, "_t", t)
        object.__setattr__(self, "_v", v)

    def __call__(self, t: np.ndarray) -> np.ndarray:
        return np.interp(t, self._t, self._v)


Shape = Union[Step, Ramp, Sine, Chirp, Trapezoid, Constant, Tabulated]
_SHAPES = {c.__name__: c for c in (Step, Ramp, Sine, Chirp, Trapezoid, Constant, Tabulated)}


def _shape_to_dict(s: Shape) -> dict[str, Any]:
    return {"shape": type(s).__name__, **asdict(s)}


# What a profile read back from data (trace metadata) may hold. Far beyond any actuator's
# test, so that only nonsense or a unit slip is refused: the time of a shape [s], the
# duration [s], a command magnitude [rad], a load magnitude [N m], a frequency [Hz], a
# speed [rad/s], an acceleration [rad/s^2], the samples of a Tabulated shape.
MAX_TIME_S = 1e4
MAX_COMMAND_RAD = 1e6
MAX_LOAD_NM = 1e5
MAX_FREQUENCY_HZ = 1e5
MAX_SPEED = 1e6
MAX_ACCELERATION = 1e9
MAX_TABULATED = 10_000_000

# field -> (unit, largest magnitude, may be +inf); "magnitude" fields take the side's unit
_FIELDS: dict[str, tuple[str, float, bool]] = {
    "t0": ("s", MAX_TIME_S, False), "t1": ("s", MAX_TIME_S, True),
    "frequency": ("Hz", MAX_FREQUENCY_HZ, False), "f0": ("Hz", MAX_FREQUENCY_HZ, False),
    "f1": ("Hz", MAX_FREQUENCY_HZ, False), "v_max": ("rad/s", MAX_SPEED, False),
    "a_max": ("rad/s^2", MAX_ACCELERATION, False),
}
_MAGNITUDES = ("height", "amplitude", "value", "values")


def _number(where: str, value: Any, unit: str, largest: float, *, inf_ok: bool = False) -> float:
    """``value`` as a float, or a ProfileError "``where``: expected a number in ``unit``"."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        got = f"the string {shown(value)}" if isinstance(value, str) else shown(value)
        raise ProfileError(f"{where}: expected a number in {unit}, got {got}")
    v = float(value)
    if math.isnan(v) or (math.isinf(v) and not (inf_ok and v > 0)):
        raise ProfileError(f"{where}: expected a finite number in {unit}, got {value!r}")
    if math.isfinite(v) and abs(v) > largest:
        raise ProfileError(f"{where} = {v:g} {unit} is beyond any actuator test (at most "
                           f"{largest:g} {unit} in magnitude); check the value and its unit "
                           f"({unit})")
    return v


def _samples(where: str, value: Any, unit: str, largest: float) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)):
        raise ProfileError(f"{where}: expected a list of numbers in {unit}, got {shown(value)}")
    if len(value) > MAX_TABULATED:
        raise ProfileError(f"{where}: {len(value)} samples, more than {MAX_TABULATED}; "
                           "decimate the tabulated profile")
    return tuple(_number(f"{where}[{i}]", x, unit, largest) for i, x in enumerate(value))


def _shape_from_dict(d: Any, where: str = "shape", side: str = "command") -> Shape:
    """A shape from its dict, every field checked: its type, its unit (``side``: a
    ``"command"`` magnitude is in rad, a ``"load"`` one in N m) and a plausible size."""
    if not isinstance(d, dict):
        raise ProfileError(f"{where}: expected an object such as {{\"shape\": \"Step\", "
                           f"\"t0\": 0.02, \"height\": 0.5}}, got {shown(d)}")
    d = dict(d)
    kind = d.pop("shape", None)
    if kind not in _SHAPES:
        raise ProfileError(f"{where}: unknown profile shape {shown(kind)}; known: {', '.join(_SHAPES)}")
    cls = _SHAPES[kind]
    known = {f.name: f for f in fields(cls)}
    extra = sorted(set(d) - set(known), key=str)
    if extra:
        raise ProfileError(f"{where}: unknown field(s) {shown(extra)} of {kind}; its fields: "
                           f"{', '.join(known)}")
    missing = [n for n, f in known.items() if n not in d and f.default is MISSING]
    if missing:
        raise ProfileError(f"{where}: {kind} is missing {', '.join(missing)}")
    unit, largest = ("rad", MAX_COMMAND_RAD) if side == "command" else ("N m", MAX_LOAD_NM)
    kw: dict[str, Any] = {}
    for name, value in d.items():
        at = f"{where}.{name}"
        if name == "t":
            kw[name] = _samples(at, value, "s", MAX_TIME_S)
        elif name == "values":
            kw[name] = _samples(at, value, unit, largest)
        elif name in _MAGNITUDES:
            kw[name] = _number(at, value, unit, largest)
        else:
            f_unit, f_largest, inf_ok = _FIELDS[name]
            kw[name] = _number(at, value, f_unit, f_largest, inf_ok=inf_ok)
    try:
        return cls(**kw)
    except ProfileError as exc:
        raise ProfileError(f"{where}: {exc}") from None


@dataclass(frozen=True)
class Profile:
    """Position command and load torque over ``[0, duration]``."""

    duration: float
    command: tuple[Shape, ...] = ()
    load: tuple[Shape, ...] = ()
    name: str = "custom"
    description: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise ProfileError(f"Profile.duration [s] must be > 0, got {self.duration!r}")
        object.__setattr__(self, "command", tuple(self.command))
        object.__setattr__(self, "load", tuple(self.load))

    def theta_ref(self, t: np.ndarray) -> np.ndarray:
        """Position command [rad] at times t [s]."""
        t = np.asarray(t, dtype=float)
        return sum((s(t) for s in self.command), np.zeros_like(t))

    def load_torque(self, t: np.ndarray) -> np.ndarray:
        """External load torque [N m] at times t [s]."""
        t = np.asarray(t, dtype=float)
        return sum((s(t) for s in self.load), np.zeros_like(t))

    def grid(self, T_s: float) -> np.ndarray:
        """Sampling instants ``k*T_s`` covering the duration."""
        n = int(round(self.duration / T_s))
        return np.arange(n) * T_s

    @classmethod
    def from_samples(cls, t, theta_ref, load_torque=None, name: str = "recorded") -> "Profile":
        """A profile that replays a recorded command (and load torque) sampled at ``t``.

        Time is shifted so that the first sample is at 0; the duration covers
        the samples plus one step, so that ``grid(dt)`` returns one point per sample.
        """
        t = np.asarray(t, dtype=float)
        t = t - t[0]
        dt = float(np.mean(np.diff(t))) if t.size > 1 else 0.0
        load = (Tabulated(t, load_torque),) if load_torque is not None else ()
        return cls(duration=float(t[-1] + dt), command=(Tabulated(t, theta_ref),), load=load,
                   name=name, description=f"recorded command, {t.size} samples")

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "duration": self.duration, "description": self.description,
                "command": [_shape_to_dict(s) for s in self.command],
                "load": [_shape_to_dict(s) for s in self.load]}

    @classmethod
    def from_dict(cls, d: Any, where: str = "profile") -> "Profile":
        """Rebuild a profile from :meth:`to_dict`'s data (e.g. trace metadata), checking
        every field: a ProfileError names it by its path (``where``, then e.g.
        ``.command[0].amplitude``), what was expected, with its unit, and what came."""
        if not isinstance(d, dict):
            raise ProfileError(f"{where}: expected an object with duration, command and load, "
                               f"got {shown(d)}")
        extra = sorted(set(d) - {"name", "duration", "description", "command", "load"}, key=str)
        if extra:
            raise ProfileError(f"{where}: unknown field(s) {shown(extra)}; a profile has name, "
                               "duration, description, command and load")
        if "duration" not in d:
            raise ProfileError(f"{where}: cannot rebuild a profile without its duration [s]")
        duration = _number(f"{where}.duration", d["duration"], "s", MAX_TIME_S)
        sides: dict[str, tuple[Shape, ...]] = {}
        for side in ("command", "load"):
            shapes = d.get(side, [])
            if not isinstance(shapes, (list, tuple)):
                raise ProfileError(f"{where}.{side}: expected a list of shapes, got {shown(shapes)}")
            sides[side] = tuple(_shape_from_dict(x, f"{where}.{side}[{i}]", side)
                                for i, x in enumerate(shapes))
        for key in ("name", "description"):
            if key in d and not isinstance(d[key], str):
                raise ProfileError(f"{where}.{key}: expected text, got {shown(d[key])}")
        try:
            return cls(duration=duration, command=sides["command"], load=sides["load"],
                       name=d.get("name", "custom"), description=d.get("description", ""))
        except ProfileError as exc:
            raise ProfileError(f"{where}: {exc}") from None


def diagnostic(load_torque: float = 0.0) -> Profile:
    """The default diagnostic test, 0.5 s, designed so that every fault shows.

    ====================  ==========================================  ======================
    time [s]              command                                     makes visible
    ====================  ==========================================  ======================
    0.00 - 0.02           hold at 0                                   initial state
    0.02                  step +0.5 rad, then hold to 0.10            gain drift (k8): the
                                                                      step response; friction
                                                                      (k1) at standstill
    0.10 - 0.25           ramp +3 pi rad (1.5 revolutions, 63 rad/s)  friction and viscous
                                                                      current plateau (k1);
                                                                      eccentricity (k6, k7)
                                                                      over > 1 revolution;
                                                                      short circuits (k3-5)
                                                                      under steady current
    0.25 - 0.30           hold                                        stop, load overrun
    0.30 - 0.38           ramp -2 pi rad (reversal, -79 rad/s)        backlash (k2): the gap
                                                                      crossed at reversal
    0.43                  step -0.5 rad, hold to 0.50                 gain drift (k8) again
    ====================  ==========================================  ======================

    The motor turns over about 9.9 rad in all (more than one revolution, as
    Eq. 2's eccentricity follows the mechanical angle), the steps drive the
    current near 4 A peak so short circuits change measurable currents.
    """
    return Profile(
        duration=0.5,
        command=(Step(0.02, 0.5), Ramp(0.10, 0.25, 3 * math.pi), Ramp(0.30, 0.38, -2 * math.pi),
                 Step(0.43, -0.5)),
        load=(Constant(load_torque),) if load_torque else (),
        name="diagnostic",
        description="step, hold, 1.5 revolutions, hold, reversal, step (0.5 s)",
    )


def step(height: float = 1.0, t0: float = 0.02, duration: float = 0.3) -> Profile:
    """A single position step of ``height`` rad at ``t0``."""
    return Profile(duration, (Step(t0, height),), name="step")


def ramp(height: float = 2 * math.pi, t0: float = 0.02, t1: float = 0.22,
         duration: float = 0.3) -> Profile:
    """A constant-speed move of ``height`` rad between ``t0`` and ``t1``."""
    return Profile(duration, (Ramp(t0, t1, height),), name="ramp")


def sine(amplitude: float = 4.0, frequency: float = 2.0, duration: float = 0.52,
         t0: float = 0.02) -> Profile:
    """A sinusoidal position command from ``t0`` on, after a hold at 0 (reversals every
    half period).

    The defaults fit the diagnosis as the :func:`diagnostic` profile does, on the
    preset and on actuators like it: one period of 2 Hz in 0.5 s, +-4 rad (8 rad of
    motion, more than the revolution the eccentricity needs), two reversals (the
    backlash), a peak speed of 50 rad/s and a peak acceleration of 630 rad/s^2 (under
    1 N m of inertia torque on the preset, whose motor gives 18 N m).
    """
    return Profile(duration, (Sine(amplitude, frequency, t0),), name="sine",
                   description=f"sine +-{amplitude:g} rad at {frequency:g} Hz from {t0:g} s "
                               f"({duration:g} s)")


def chirp(amplitude: float = 4.0, f0: float = 1.0, f1: float = 5.0, duration: float = 0.62,
          t0: float = 0.02) -> Profile:
    """A sinusoidal command whose frequency sweeps linearly from ``f0`` to ``f1`` [Hz]
    between ``t0`` and the end, after a hold at 0.

    The defaults: +-4 rad from 1 Hz to 5 Hz in 0.6 s (1.8 periods, three reversals, more
    than a revolution of motion), a peak speed of about 120 rad/s and a peak acceleration
    of about 3,900 rad/s^2 at the end (6 N m of inertia torque on the preset, a third of
    its 18 N m): the sweep shows the drive's response at several speeds in one test.
    """
    return Profile(duration, (Chirp(amplitude, f0, f1, t0, duration),), name="chirp",
                   description=f"chirp +-{amplitude:g} rad, {f0:g} to {f1:g} Hz from {t0:g} s "
                               f"({duration:g} s)")


def trapezoid(height: float = 2 * math.pi, v_max: float = 80.0, a_max: float = 4000.0,
              t0: float = 0.02, duration: float = 0.3) -> Profile:
    """A point-to-point move with a trapezoidal speed profile."""
    return Profile(duration, (Trapezoid(t0, height, v_max, a_max),), name="trapezoid")


PROFILES = {"diagnostic": diagnostic, "step": step, "ramp": ramp, "sine": sine,
            "chirp": chirp, "trapezoid": trapezoid}


def get_profile(name: str) -> Profile:
    """A built-in profile by name, with its default arguments."""
    try:
        return PROFILES[name]()
    except KeyError:
        raise ProfileError(f"unknown profile {name!r}; choose one of {', '.join(PROFILES)}, "
                           "or a CSV file of t, theta_ref (read_profile)") from None


#: Most samples a profile file may hold (a 0.5 s test at 8 kHz is 4,000).
MAX_PROFILE_SAMPLES = 1_000_000
#: Shortest profile a file may describe [s]: a diagnosis reads at least 100 samples
#: (emaphm.traces.MIN_SAMPLES), 12.5 ms at the preset's 8 kHz control rate.
MIN_PROFILE_DURATION_S = 100 / 8000.0
#: Longest profile a file may describe [s]: a simulation of the plant takes about as long
#: as the test; a diagnosis needs one profile of about 0.5 s.
MAX_PROFILE_DURATION_S = 60.0


def read_profile(path: Any) -> Profile:
    """A position command read from a CSV file: columns ``t`` [s] and ``theta_ref`` [rad]
    (others are ignored, so a trace file is a profile too), written as the trace reader
    takes them: ``,`` ``;`` or tab between fields, ``#`` comment lines, names as ``name
    [unit]`` or a units row. Without a unit they are s and rad; a declared unit of the
    right quantity is converted (``t [ms]``, ``theta_ref [deg]``, ``[rev]``:
    :mod:`emaphm.quantities`). The times must be finite and strictly increasing; the
    command is replayed relative to its first sample (the plant starts at rest at 0) from
    time 0, linearly interpolated (:class:`Tabulated`). A ProfileError names the file,
    what is wrong and the fix, in one line."""
    from pathlib import Path

    from .quantities import QuantityError, measure
    from .traces import TraceError
    from .traces.csv_format import collect, csv_blocks, sniff_csv
    from .traces.limits import TooManySamples

    p = Path(path)
    if p.suffix.lower() != ".csv":
        raise ProfileError(f"profile file {p}: expected a .csv file of columns t, theta_ref "
                           f"(s, rad), got {p.suffix or 'no suffix'}")
    if not p.is_file():
        raise ProfileError(f"profile file {p} does not exist" if not p.exists() else
                           f"profile file {p} is not a file; give a CSV file of t, theta_ref")
    try:
        layout = sniff_csv(p)
        if layout.decimal == ",":
            raise ProfileError(f"profile file {p}: the numbers are written with a decimal comma; "
                               "write them with decimal points")
        names = list(layout.names)
        missing = [c for c in ("t", "theta_ref") if c not in names]
        if missing:
            raise ProfileError(f"profile file {p}: no column {', '.join(missing)}; the header must "
                               f"name t [s] and theta_ref [rad] (found {', '.join(names[:8])})")
        scale = []
        for c, kind in (("t", "time"), ("theta_ref", "angle")):
            unit = (layout.units[names.index(c)] or "").strip().strip("[]").strip()
            scale.append(measure(unit, kind, where=f"profile file {p}: column {c}").factor
                         if unit not in ("", "-") else 1.0)
        t, theta = collect(csv_blocks(layout, [names.index("t"), names.index("theta_ref")],
                                      max_rows=MAX_PROFILE_SAMPLES), 2)
    except TooManySamples as exc:
        raise ProfileError(f"profile file {p}: {exc.found}, above the {exc.limit:,} rows a "
                           "profile file may hold (a 0.5 s test at 8 kHz is 4,000); give one "
                           "test of about 0.5 s") from None
    except (TraceError, QuantityError) as exc:
        text = str(exc)
        text = text[len(f"{p}: "):] if text.startswith(f"{p}: ") else text
        raise ProfileError(text if text.startswith("profile file") else
                           f"profile file {p}: {text}") from None
    return _profile_of_samples(t * scale[0], theta * scale[1], f"profile file {p}", p.stem)


def _profile_of_samples(t: np.ndarray, theta: np.ndarray, where: str, name: str) -> Profile:
    """The checked samples of a profile file as a :class:`Profile` (see :func:`read_profile`)."""
    if t.size < 2:
        raise ProfileError(f"{where}: {t.size} sample(s); a profile needs at least two rows of "
                           "t, theta_ref")
    for label, x in (("t", t), ("theta_ref", theta)):
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.argmax(bad))
            raise ProfileError(f"{where}: column {label} holds {int(bad.sum())} empty or "
                               f"non-finite value(s), the first in data row {i + 1}; fill them in "
                               "or remove those rows")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise ProfileError(f"{where}: time must increase strictly from row to row, but t goes "
                           f"from {t[i]:.9g} to {t[i + 1]:.9g} s at data row {i + 2}; sort the "
                           "rows by time and remove repeated times")
    span = float(t[-1] - t[0])
    if span < MIN_PROFILE_DURATION_S:
        raise ProfileError(f"{where}: the command lasts {span:.6g} s ({t.size} rows), shorter "
                           f"than the {MIN_PROFILE_DURATION_S:g} s a diagnosis needs (100 samples "
                           "at 8 kHz); give a test of about 0.5 s (is t in s?)")
    if span > MAX_PROFILE_DURATION_S:
        raise ProfileError(f"{where}: the command lasts {span:.6g} s, longer than "
                           f"{MAX_PROFILE_DURATION_S:g} s (is t in ms? divide it by 1000); a "
                           "diagnosis needs one test of about 0.5 s")
    if np.ptp(theta) == 0.0:
        raise ProfileError(f"{where}: theta_ref is {theta[0]:g} rad in every row: a command "
                           "that does not move the actuator identifies nothing; give a test "
                           "that moves it (e.g. the built-in diagnostic profile)")
    theta = theta - theta[0]
    peak = float(np.max(np.abs(theta)))
    if peak > MAX_COMMAND_RAD:
        raise ProfileError(f"{where}: theta_ref moves {peak:.6g} rad, beyond any actuator test "
                           f"(at most {MAX_COMMAND_RAD:g} rad); give it in rad")
    return Profile.from_samples(t, theta, name=name)
