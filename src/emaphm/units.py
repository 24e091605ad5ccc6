"""Production units: an actuator as built, not as its data sheet says.

No real unit matches its data-sheet preset: inertia, magnet flux, winding
resistance (temperature), inductance and friction spread within tolerances,
each current sensor has its own gain and offset, and the bench may carry a
constant load it does not report. :func:`draw_unit` draws such a unit from
an explicit seed; the reference plant simulates it, the monitoring model
still assumes the data sheet (until the unit is calibrated).

Tolerances are intervals ``(lo, hi)`` drawn uniformly: relative deviations
for the physical parameters (``J = (-0.1, 0.1)`` is +-10 %), absolute ones for
the sensor offset [A] and the unreported load [N m]. The defaults
(:data:`DEFAULT_TOLERANCES`) are a plausible spread for a servo actuator:

===================  ==============  ==============================================
field                default         what it scales
===================  ==============  ==============================================
``J``                -10 .. +10 %    motor and load inertia (same factor)
``flux``             -5 .. +5 %      magnet flux: back-EMF coefficient = torque constant
``R``                0 .. +25 %      winding resistance (a warm winding: +25 % at ~85 C)
``L``                -5 .. +5 %      synchronous inductance
``friction``         -20 .. +20 %    dry friction FSJ and FDJ (same factor)
``viscous``          -20 .. +20 %    viscous friction C_m
``sensor_gain``      -3 .. +3 %      each phase's current sensor gain, independently
``sensor_offset``    -20 .. +20 mA   each phase's current sensor offset, independently
``load``             -0.1 .. +0.1    constant load torque [N m] the bench does not report
``stiffness``        -15 .. +15 %    backlash contact stiffness K_c (the gear train's)
``damping``          -30 .. +30 %    backlash contact damping D_c
===================  ==============  ==============================================

The drive keeps its data-sheet settings (``Controller.k_T``): a unit's flux
deviation is not known to the firmware.
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .params import ActuatorParams, read_toml
from .seeds import check_seed

__all__ = ["Tolerances", "DEFAULT_TOLERANCES", "Unit", "draw_unit", "nominal_unit",
           "load_tolerances"]

Interval = tuple[float, float]


@dataclass(frozen=True)
class Tolerances:
    """Uniform intervals of a unit's deviations from its data sheet (see module doc)."""

    J: Interval = (-0.10, 0.10)
    flux: Interval = (-0.05, 0.05)
    R: Interval = (0.0, 0.25)
    L: Interval = (-0.05, 0.05)
    friction: Interval = (-0.20, 0.20)
    viscous: Interval = (-0.20, 0.20)
    sensor_gain: Interval = (-0.03, 0.03)
    sensor_offset: Interval = (-0.02, 0.02)
    load: Interval = (-0.1, 0.1)
    stiffness: Interval = (-0.15, 0.15)
    damping: Interval = (-0.30, 0.30)

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            try:
                lo, hi = (float(x) for x in v)
            except (TypeError, ValueError):
                raise ValueError(f"tolerance {f.name} must be an interval [lo, hi], got {v!r}") \
                    from None
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise ValueError(f"tolerance {f.name} = [{lo:g}, {hi:g}] must be finite with "
                                 "lo <= hi")
            relative = f.name not in ("sensor_offset", "load")
            if relative and not (lo > -0.9 and hi < 2.0):
                raise ValueError(f"tolerance {f.name} = [{lo:g}, {hi:g}] is a relative deviation "
                                 "and must lie within (-0.9, 2): 0.1 means +10 %")
            if f.name == "sensor_offset" and max(abs(lo), abs(hi)) > 1.0:
                raise ValueError(f"tolerance sensor_offset = [{lo:g}, {hi:g}] A is beyond 1 A; "
                                 "give it in amperes (0.02 = 20 mA)")
            if f.name == "load" and max(abs(lo), abs(hi)) > 5.0:
                raise ValueError(f"tolerance load = [{lo:g}, {hi:g}] N m is beyond 5 N m")
            object.__setattr__(self, f.name, (lo, hi))

    def to_dict(self) -> dict[str, list[float]]:
        return {k: list(v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, source: str = "tolerances") -> "Tolerances":
        if not isinstance(data, dict):
            raise ValueError(f"{source}: expected a table of tolerances, got {type(data).__name__}")
        data = data.get("tolerances", data)
        known = {f.name for f in fields(cls)}
        extra = set(data) - known
        if extra:
            raise ValueError(f"{source}: unknown tolerance(s) {sorted(extra)}; known: "
                             + ", ".join(sorted(known)))
        try:
            return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in data.items()})
        except ValueError as exc:          # name the file
            raise ValueError(f"{source}: {exc}") from None


DEFAULT_TOLERANCES = Tolerances()


def load_tolerances(path: str | os.PathLike[str]) -> Tolerances:
    """Tolerances from a TOML file: ``[tolerances]`` with ``name = [lo, hi]`` lines;
    names left out keep the defaults."""
    p = Path(path)
    data = read_toml(p, "tolerance file")
    return Tolerances.from_dict(data, source=str(p))


@dataclass(frozen=True)
class Unit:
    """One production unit: its true parameters, its current sensors and a hidden load.

    ``deviations`` are the drawn relative (or absolute) deviations by tolerance name,
    ``seed`` the seed they were drawn with (None for the nominal unit).
    """

    params: ActuatorParams
    sensor_gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    sensor_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    load: float = 0.0
    seed: int | None = None
    deviations: dict[str, Any] | None = None

    def to_dict(self, params: bool = False) -> dict[str, Any]:
        """The unit's truth (recorded in a simulated trace's metadata; diagnosis never reads
        it); with ``params`` its true parameters too (``"params"``), which :meth:`from_dict`
        needs (the trace's metadata has the data sheet's beside it)."""
        d = {"seed": self.seed, "sensor_gain": list(self.sensor_gain),
             "sensor_offset": list(self.sensor_offset), "unreported_load": self.load,
             "deviations": self.deviations or {}}
        if params:
            d["params"] = self.params.to_dict()
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], params: ActuatorParams | None = None) -> "Unit":
        """The unit :meth:`to_dict` wrote; its true parameters from ``data["params"]``
        (``to_dict(params=True)``) or ``params``."""
        if "params" in data:
            params = ActuatorParams.from_dict(data["params"], source="unit params")
        if params is None:
            raise ValueError("this unit was written without its parameters: write it with "
                             "to_dict(params=True), or give params= (its true ActuatorParams)")
        return cls(params=params, sensor_gain=tuple(data["sensor_gain"]),
                   sensor_offset=tuple(data["sensor_offset"]), load=data["unreported_load"],
                   seed=data["seed"], deviations=dict(data["deviations"]) or None)


def nominal_unit(params: ActuatorParams, *, load: float = 0.0) -> Unit:
    """The unit exactly as its data sheet says (optionally with an unreported load)."""
    return Unit(params=params, load=float(load))


def draw_unit(params: ActuatorParams, seed: int,
              tolerances: Tolerances = DEFAULT_TOLERANCES) -> Unit:
    """Draw a unit around the data sheet ``params`` (healthy; faults are applied later)."""
    check_seed(seed, "unit seed")
    rng = np.random.default_rng([0x756E6974, int(seed)])    # "unit": apart from noise seeds
    t = tolerances

    def u(iv: Interval, size=None):
        return rng.uniform(iv[0], iv[1], size)

    d = {"J": float(u(t.J)), "flux": float(u(t.flux)), "R": float(u(t.R)), "L": float(u(t.L)),
         "friction": float(u(t.friction)), "viscous": float(u(t.viscous)),
         "sensor_gain": [float(x) for x in u(t.sensor_gain, 3)],
         "sensor_offset": [float(x) for x in u(t.sensor_offset, 3)],
         "load": float(u(t.load))}
    d["stiffness"] = float(u(t.stiffness))     # drawn last: the draws above keep their values
    d["damping"] = float(u(t.damping))
    m, tr, ld = params.motor, params.transmission, params.load
    motor = replace(m, J_m=m.J_m * (1 + d["J"]), c0=tuple(c * (1 + d["flux"]) for c in m.c0),
                    R=tuple(r * (1 + d["R"]) for r in m.R), L=tuple(x * (1 + d["L"]) for x in m.L),
                    C_m=m.C_m * (1 + d["viscous"]))
    trans = replace(tr, FSJ=tr.FSJ * (1 + d["friction"]), FDJ=tr.FDJ * (1 + d["friction"]),
                    K_c=tr.K_c * (1 + d["stiffness"]), D_c=tr.D_c * (1 + d["damping"]))
    load = replace(ld, J_l=ld.J_l * (1 + d["J"]))
    # the drive's own settings stay the data sheet's (emaphm.params.Controller.resolved)
    drive = params.controller.kept_for(m, ld, motor, load)
    unit_params = replace(params, motor=motor, transmission=trans, load=load, controller=drive)
    return Unit(params=unit_params, sensor_gain=tuple(1 + g for g in d["sensor_gain"]),
                sensor_offset=tuple(d["sensor_offset"]), load=d["load"], seed=int(seed),
                deviations=d)
