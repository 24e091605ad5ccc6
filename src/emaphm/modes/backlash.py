"""Backlash (k2 of the paper's vector): the width x (1 + 99 k2)."""

from __future__ import annotations

from ..faults import backlash_scale
from .base import Fault, FaultMode, Injection, Reading


def read(r: Reading) -> list[Fault]:
    k2 = float(r.k[1])
    if not k2 > r.thresholds.backlash:
        return []
    bs = float(backlash_scale(k2))
    return [Fault("backlash", "k2", k2, k2,
                  f"backlash {bs:.1f}x nominal ({r.params.transmission.backlash * bs * 1e3:.2f} "
                  "mrad)")]


def inject(severity: float, phase: str | None = None) -> Injection:
    """Backlash ``severity`` x nominal (1 to 100)."""
    if not 1.0 <= severity <= 100.0:
        raise ValueError(f"backlash is 1 to 100 x nominal, got {severity:g}")
    return Injection(k={1: (severity - 1.0) / 99.0})


def measure(r: Reading) -> dict[str, float]:
    return {"backlash": float(r.k[1])}


MODE = FaultMode("backlash", "backlash", threshold=0.034, read=read, inject=inject,
                 severity_unit="x nominal backlash", grid=(5.0, 10.0, 25.0, 50.0),
                 k_components=(1,), measure=measure, magnitude=lambda s: abs(s - 1.0))
