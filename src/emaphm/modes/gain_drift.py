"""Proportional gain drift (k8 of the paper's vector): Kp x (0.5 + k8)."""

from __future__ import annotations

from ..faults import K_NOMINAL, gain_scale
from .base import Fault, FaultMode, Indicator, Injection, Reading


def read(r: Reading) -> list[Fault]:
    k8 = float(r.k[7])
    drift = k8 - float(K_NOMINAL[7])
    if not abs(drift) > r.thresholds.gain_drift:
        return []
    g = float(gain_scale(k8))
    Kp = r.params.controller.Kp
    return [Fault("gain_drift", "k8", k8, abs(drift) / 0.5,
                  f"proportional gain {100 * (g - 1):+.0f}% (Kp {Kp * g:.1f} 1/s instead of "
                  f"{Kp:.1f})")]


def inject(severity: float, phase: str | None = None) -> Injection:
    """The proportional gain at ``severity`` x nominal (0.5 to 1.5)."""
    if not 0.5 <= severity <= 1.5:
        raise ValueError(f"a proportional gain is 0.5 to 1.5 x nominal, got {severity:g}")
    return Injection(k={7: severity - 0.5})


def measure(r: Reading) -> dict[str, float]:
    return {"gain_drift": abs(float(r.k[7]) - float(K_NOMINAL[7]))}


#: Trended by ``|k8 - 0.5|`` (its series signed along a history, k8 - 0.5 with the sign of
#: the latest drift, in [-0.5, 0.5]). Failure at 0.25, the proportional gain 25 % off (the
#: paper's fault magnitudes 0.25 and 0.75 around the nominal 0.5): the position loop's
#: damping and bandwidth change enough to miss its specification. Model discrepancy 0.0051.
INDICATORS = (Indicator("gain_drift", "gain drift (|k8 - 0.5|)", failure=0.25,
                        discrepancy=0.0051, component=7, center=float(K_NOMINAL[7]),
                        bounds=(-0.5, 0.5)),)

MODE = FaultMode("gain_drift", "proportional gain drift", threshold=0.015, read=read,
                 inject=inject, severity_unit="x nominal proportional gain",
                 grid=(0.9, 0.95, 1.05, 1.1),
                 k_components=(7,), measure=measure, magnitude=lambda s: abs(s - 1.0),
                 indicators=INDICATORS, in_controller=True)
