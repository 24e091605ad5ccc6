"""Dry friction (k1 of the paper's vector): FSJ and FDJ x (1 + 2 k1)."""

from __future__ import annotations

from ..faults import friction_scale
from .base import Fault, FaultMode, Indicator, Injection, Reading


def read(r: Reading) -> list[Fault]:
    k1 = float(r.k[0])
    if not k1 > r.thresholds.friction:
        return []
    fs = float(friction_scale(k1))
    tr = r.params.transmission
    return [Fault("friction", "k1", k1, k1,
                  f"dry friction {fs:.2f}x nominal (dynamic {tr.FDJ * fs:.3f} N m, "
                  f"static {tr.FSJ * fs:.3f} N m)")]


def inject(severity: float, phase: str | None = None) -> Injection:
    """Friction ``severity`` x nominal (1 to 3)."""
    if not 1.0 <= severity <= 3.0:
        raise ValueError(f"friction is 1 to 3 x nominal, got {severity:g}")
    return Injection(k={0: (severity - 1.0) / 2.0})


def measure(r: Reading) -> dict[str, float]:
    return {"friction": float(r.k[0])}


#: Trended by k1. Failure at 0.5, twice the nominal dry friction: the position loop still
#: tracks, but the stick-slip dead zone and the current spent on friction double; beyond it
#: the torque margin of a flight-control actuator shrinks fast. Model discrepancy 0.053
#: (mean +0.039): the plant's Stribeck drop, which the monitoring model lacks, reads as
#: more Coulomb friction, more so as the friction grows (how it was measured:
#: :data:`emaphm.prognosis.trends.MODEL_DISCREPANCY`).
INDICATORS = (Indicator("friction", "friction (k1)", failure=0.5, discrepancy=0.053,
                        component=0),)

MODE = FaultMode("friction", "dry friction", threshold=0.100, read=read, inject=inject,
                 severity_unit="x nominal friction", grid=(1.25, 1.5, 2.0, 2.5),
                 k_components=(0,), measure=measure, magnitude=lambda s: abs(s - 1.0),
                 indicators=INDICATORS)
