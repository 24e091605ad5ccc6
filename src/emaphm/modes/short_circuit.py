"""Inter-turn short circuit of one phase (k3..k5 of the paper's vector).

Under the ``physical`` fault model a component is the fraction ``mu`` of the phase's turns
bridged by the fault resistance ``Motor.R_f`` (a fault-loop current flows); under the
``paper``'s, the turns removed (``R x (1 - s)``, ``L x (1 - s)^2``).
"""

from __future__ import annotations

from ..faults import shorted_fraction
from .base import PHASES, Fault, FaultMode, Injection, Reading


def read(r: Reading) -> list[Fault]:
    faults = []
    for j, ph in enumerate(PHASES):
        kj = float(r.k[2 + j])
        if not kj > r.thresholds.short_circuit:
            continue
        s = float(shorted_fraction(kj))
        if r.fault_model == "physical":
            reading = (f"inter-turn short circuit in phase {ph}: {100 * s:.1f}% of its turns "
                       f"as seen through a fault resistance of {r.params.motor.R_f[j]:g} ohm (a "
                       "higher fault resistance needs more shorted turns for the same "
                       "fault current)")
        else:
            reading = (f"{100 * s:.0f}% of phase {ph} turns shorted "
                       f"(R x{1 - s:.2f}, L x{(1 - s) ** 2:.2f})")
        faults.append(Fault("short_circuit", f"k{3 + j}", kj, kj, reading, phase=ph))
    return faults


def inject(severity: float, phase: str | None = "A") -> Injection:
    """A shorted fraction ``severity`` (0 to 0.99) of phase ``phase``."""
    if not 0.0 <= severity <= 0.99:
        raise ValueError(f"a shorted fraction is 0 to 0.99, got {severity:g}")
    j = PHASES.index((phase or "A").upper())
    return Injection(k={2 + j: severity})


MODE = FaultMode("short_circuit", "inter-turn short circuit", threshold=0.03,
                 thresholds_by_fm={"physical": 0.018}, read=read, inject=inject,
                 severity_unit="shorted fraction of the turns", grid=(0.03, 0.05, 0.1, 0.2),
                 per_phase=True, spec="PHASE:FRACTION")
