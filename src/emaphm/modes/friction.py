"""Dry friction (k1 of the paper's vector): FSJ and FDJ x (1 + 2 k1)."""

from __future__ import annotations

from typing import Any

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


def hypothesis(problem: Any, ident: Any, diag: Any) -> tuple[str, ...] | None:
    """When a friction read leaves a misfit and the unit's file states no Stribeck drop:
    the dry friction's Stribeck speed searched beside k (``"stribeck"``), with the
    problem's own parameters. The two-level friction reads the plant's drop as more
    Coulomb friction, the more so as it grows, until the fit fails: friction x2 and x2.5
    on ema-270v-750w's data sheet read 2.14x and 2.68x, `unexplained` on 5 of 6 seeds.
    (A calibrated unit has its speed from ``emaphm calibrate``.)"""
    if "stribeck" in problem.nuisance or problem.params.transmission.omega_s > 0.0:
        return None
    misfit = diag.unexplained is not None and diag.unexplained.reason == "misfit"
    if not (misfit and float(ident.k[0]) > diag.thresholds.friction):
        return None
    return tuple(problem.nuisance) + ("stribeck",)


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
#: (mean +0.039), measured on data sheets: the plant's Stribeck drop, which a data sheet's
#: two-level friction lacks (a calibrated unit has it, docs/commissioning.md), reads as
#: more Coulomb friction, more so as the friction grows (how it was measured:
#: :data:`emaphm.prognosis.trends.MODEL_DISCREPANCY`).
INDICATORS = (Indicator("friction", "friction (k1)", failure=0.5, discrepancy=0.053,
                        component=0),)

MODE = FaultMode("friction", "dry friction", threshold=0.100, read=read, inject=inject,
                 severity_unit="x nominal friction", grid=(1.25, 1.5, 2.0, 2.5),
                 k_components=(0,), measure=measure, magnitude=lambda s: abs(s - 1.0),
                 hypothesis=hypothesis, indicators=INDICATORS)
