"""Static eccentricity (k6 modulus, k7 phase of the paper's vector, Eq. 2)."""

from __future__ import annotations

import math

from ..faults import eccentricity_phase
from .base import Fault, FaultMode, Indicator, Injection, Reading


def read(r: Reading) -> list[Fault]:
    k6 = float(r.k[5])
    if not k6 > r.thresholds.eccentricity:
        return []
    phase_deg = math.degrees(float(eccentricity_phase(r.k[6])))
    return [Fault("eccentricity", "k6,k7", k6, k6,
                  f"static eccentricity {100 * k6:.0f}% of the air gap at {phase_deg:+.0f} deg")]


def inject(severity: float, phase: str | None = None) -> Injection:
    """An eccentricity of ``severity`` of the air gap (0 to 1), at phase angle 0."""
    if not 0.0 <= severity <= 1.0:
        raise ValueError(f"an eccentricity is 0 to 1 of the air gap, got {severity:g}")
    return Injection(k={5: severity, 6: 0.5})


def measure(r: Reading) -> dict[str, float]:
    return {"eccentricity": float(r.k[5])}


#: Trended by k6. Failure at 0.5, half the air gap: the unbalanced magnetic pull grows and
#: rotor-stator rub becomes a risk. Model discrepancy 0.0070.
INDICATORS = (Indicator("eccentricity", "eccentricity (k6)", failure=0.5, discrepancy=0.0070,
                        component=5),)

MODE = FaultMode("eccentricity", "static eccentricity", threshold=0.015, read=read,
                 inject=inject, severity_unit="fraction of the air gap",
                 grid=(0.02, 0.05, 0.1, 0.25),
                 k_components=(5, 6), measure=measure, indicators=INDICATORS)
