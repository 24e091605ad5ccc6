"""Backlash (k2 of the paper's vector): the width x (1 + 99 k2); on a transmission whose
data sheet states none, ``BACKLASH_FROM_ZERO k2`` (:func:`emaphm.faults.backlash_width`)."""

from __future__ import annotations

from ..faults import BACKLASH_FROM_ZERO, backlash_scale, backlash_width
from .base import Fault, FaultMode, Indicator, Injection, Reading


def read(r: Reading) -> list[Fault]:
    k2 = float(r.k[1])
    if not k2 > r.thresholds.backlash:
        return []
    nominal = r.params.transmission.backlash
    width = float(backlash_width(nominal, k2))
    if nominal > 0.0:
        text = f"backlash {float(backlash_scale(k2)):.1f}x nominal ({width * 1e3:.2f} mrad)"
    else:
        text = (f"backlash {width * 1e3:.2f} mrad where the data sheet states none (k2 = 1 is "
                f"{BACKLASH_FROM_ZERO * 1e3:g} mrad)")
    return [Fault("backlash", "k2", k2, k2, text)]


def inject(severity: float, phase: str | None = None) -> Injection:
    """Backlash ``severity`` x nominal (1 to 100)."""
    if not 1.0 <= severity <= 100.0:
        raise ValueError(f"backlash is 1 to 100 x nominal, got {severity:g}")
    return Injection(k={1: (severity - 1.0) / 99.0})


def measure(r: Reading) -> dict[str, float]:
    return {"backlash": float(r.k[1])}


#: Trended by k2. Failure at 0.5: 50.5x nominal, about 10 mrad of lost motion at the motor,
#: far past what a surface actuator accepts before limit-cycle oscillation (flutter)
#: concerns. Model discrepancy 0.058 (mean +0.025).
INDICATORS = (Indicator("backlash", "backlash (k2)", failure=0.5, discrepancy=0.058,
                        component=1),)

MODE = FaultMode("backlash", "backlash", threshold=0.034, read=read, inject=inject,
                 severity_unit="x nominal backlash", grid=(5.0, 10.0, 25.0, 50.0),
                 k_components=(1,), measure=measure, magnitude=lambda s: abs(s - 1.0),
                 indicators=INDICATORS)
