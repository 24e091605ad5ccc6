"""Inter-turn short circuit of one phase (k3..k5 of the paper's vector).

Under the ``physical`` fault model a component is the fraction ``mu`` of the phase's turns
bridged by the fault resistance ``Motor.R_f`` (a fault-loop current flows); under the
``paper``'s, the turns removed (``R x (1 - s)``, ``L x (1 - s)^2``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from ..faults import shorted_fraction
from .base import PHASES, Fault, FaultMode, Grid, Indicator, Injection, Reading, _number


def read(r: Reading) -> list[Fault]:
    faults = []
    loops = r.findings.get("fault_loops")
    for j, ph in enumerate(PHASES):
        kj = float(r.k[2 + j])
        if not kj > r.thresholds.short_circuit:
            continue
        s = float(shorted_fraction(kj))
        details = {}
        if r.fault_model == "physical":
            R_f = r.params.motor.R_f[j] * 10.0 ** float(r.extra.get(f"Rf_{'abc'[j]}", 0.0))
            searched = f"Rf_{'abc'[j]}" in r.extra
            reading = (f"inter-turn short circuit in phase {ph}: {100 * s:.1f}% of its turns "
                       f"through a fault resistance of {R_f:.3g} ohm"
                       + ("" if searched else " (the parameters', not searched)"))
            details = {"mu": s, "R_f_ohm": R_f}
            if loops is not None:
                details.update(loops.get(ph, {}))
                if "fault_current_a_rms" in details:
                    reading += (f": {details['fault_current_a_rms']:.2f} A rms in the fault "
                                f"loop, {details['fault_power_w']:.2f} W in the bridge, "
                                f"ampere-turns mu i_f {details['fault_mmf_a_rms']:.3g} A")
                    iv = details.get("fault_current_interval")
                    if iv is not None and iv[1] > 1.25 * iv[0]:
                        pw = details["fault_power_interval"]
                        mmf = details["fault_mmf_interval"]
                        reading += (f" (fits as well from {iv[0]:.2f} to {iv[1]:.2f} A and "
                                    f"{pw[0]:.2f} to {pw[1]:.2f} W, the ampere-turns "
                                    f"{mmf[0]:.3g} to {mmf[1]:.3g} A: a mild short's shorted "
                                    "fraction and fault resistance trade off)")
        else:
            reading = (f"{100 * s:.0f}% of phase {ph} turns shorted "
                       f"(R x{1 - s:.2f}, L x{(1 - s) ** 2:.2f})")
        faults.append(Fault("short_circuit", f"k{3 + j}", kj, kj, reading, phase=ph,
                            details=details))
    return faults


def hypothesis(problem: Any, ident: Any, diag: Any) -> tuple[str, ...] | None:
    """When a short is read or suspected (physical fault model): the fault-bridge
    resistance of its phase searched beside k, with the problem's own parameters."""
    if problem.fault_model != "physical":
        return None
    shorts = [f for f in (*diag.faults, *diag.suspected) if f.mode == "short_circuit"]
    if not shorts:
        return None
    worst = max(shorts, key=lambda f: f.k)
    name = f"Rf_{worst.phase.lower()}"
    return tuple(n for n in problem.nuisance if n != name) + (name,)


def inject(severity: float, phase: str | None = "A", R_f: float | None = None) -> Injection:
    """A shorted fraction ``severity`` (0 to 0.99) of phase ``phase``, through a fault
    resistance ``R_f`` [ohm] (default the parameters' ``Motor.R_f``)."""
    if not 0.0 <= severity <= 0.99:
        raise ValueError(f"a shorted fraction is 0 to 0.99, got {severity:g}")
    j = PHASES.index((phase or "A").upper())
    if R_f is None:
        return Injection(k={2 + j: severity})
    if not 1e-4 <= R_f <= 100.0:
        raise ValueError(f"a fault resistance is 1e-4 to 100 ohm, got {R_f:g}")

    def plant(params):
        R_fs = list(params.motor.R_f)
        R_fs[j] = float(R_f)
        return replace(params, motor=replace(params.motor, R_f=tuple(R_fs)))

    return Injection(k={2 + j: severity}, plant=plant)


def parse(fields: list[str]) -> Injection:
    """``PHASE:FRACTION[:R_F_OHM]``."""
    if len(fields) not in (2, 3) or fields[0].upper() not in PHASES:
        raise ValueError("--fault short_circuit:PHASE:FRACTION[:R_F_OHM], e.g. "
                         "short_circuit:a:0.3:0.05")
    R_f = _number(fields[2], "short_circuit R_f") if len(fields) == 3 else None
    return inject(_number(fields[1], "short_circuit"), fields[0].upper(), R_f)


def measure(r: Reading) -> dict[str, float]:
    return {"short_circuit": float(max(r.k[2:5]))}


#: The assessment's shorts: the shorted fractions of ``grid``, through a fault bridge that
#: alternates from unit to unit between a severe 0.05 ohm, the parameters' own ``R_f``
#: and a mild 0.5 ohm (each unit's short on its own phase in turn).
GRIDS = (Grid("short_circuit", "shorted fraction of the turns", (0.03, 0.05, 0.1, 0.2),
              variants=({"R_f": 0.05}, {}, {"R_f": 0.5})),)

#: Trended by each phase's component (k3..k5), one indicator per phase,
#: ``short_circuit_a`` to ``_c`` (``short_a`` to ``short_c`` before 0.7). Failure at 0.3:
#: 30 % of a phase's turns shorted (under the paper's model R x 0.7, L x 0.49, that phase's
#: back-EMF x 0.7); inter-turn shorts heat and spread quickly, so the threshold sits lower
#: than the mechanical ones. Model discrepancy 0.020 (mean +0.012), the three phases alike.
INDICATORS = tuple(Indicator(f"short_circuit_{p.lower()}", f"short circuit {p} (k{3 + j})",
                             failure=0.3, discrepancy=0.020, component=2 + j, phase=p,
                             aliases=(f"short_{p.lower()}",))
                   for j, p in enumerate(PHASES))

MODE = FaultMode("short_circuit", "inter-turn short circuit", threshold=0.03,
                 thresholds_by_fm={"physical": 0.018}, read=read, inject=inject,
                 severity_unit="shorted fraction of the turns", grid=(0.03, 0.05, 0.1, 0.2),
                 per_phase=True, spec="PHASE:FRACTION[:R_F_OHM]", parse_fields=parse,
                 hypothesis=hypothesis, measure=measure, extra_grids=GRIDS,
                 k_components=(2, 3, 4), indicators=INDICATORS)
