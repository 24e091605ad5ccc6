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
            if loops is not None and ph in loops:
                details.update(loops[ph])
                reading = _loop_words(ph, details, searched)
        else:
            reading = (f"{100 * s:.0f}% of phase {ph} turns shorted "
                       f"(R x{1 - s:.2f}, L x{(1 - s) ** 2:.2f})")
        faults.append(Fault("short_circuit", f"k{3 + j}", kj, kj, reading, phase=ph,
                            details=details))
    return faults


#: The fault loop's quantities a short reports (:func:`emaphm.fault_loops.profile`): name ->
#: the name of its interval over the fits as good.
LOOP_QUANTITIES = {"fault_current_a_rms": "fault_current_interval",
                   "fault_power_w": "fault_power_interval",
                   "fault_mmf_a_rms": "fault_mmf_interval",
                   "mu": "mu_interval", "R_f_ohm": "R_f_interval"}

#: The loop's quantities in words, by the report's names.
_WORDS = {"fault_mmf_a_rms": ("the ampere-turns mu i_f", "{:.3g} A"),
          "fault_current_a_rms": ("the loop current", "{:.3g} A"),
          "fault_power_w": ("the power in the bridge", "{:.3g} W"),
          "mu": ("the shorted fraction", "{:.1%}"),
          "R_f_ohm": ("the fault resistance", "{:.3g} ohm")}


def _loop_words(ph: str, d: dict, searched: bool) -> str:
    """A short's reading from its fault loop's report: the ampere-turns first (what the
    terminal currents carry, its severity), then the fit's fraction, bridge, current and
    power, each with its interval over the fits as good, and which of them the fit
    determines."""
    def span(q: str) -> str:
        lo, hi = d[LOOP_QUANTITIES[q]]
        fmt = _WORDS[q][1]
        for digits in (".3g", ".4g", ".5g"):          # as many as tell the ends apart
            fmt = _WORDS[q][1].replace(".3g", digits)
            if fmt.format(lo) != fmt.format(hi):
                break
        return f"{fmt.format(lo)} to {fmt.format(hi)}"

    det = set(d.get("determined", ()))
    text = (f"inter-turn short circuit in phase {ph}: ampere-turns mu i_f "
            f"{_WORDS['fault_mmf_a_rms'][1].format(d['fault_mmf_a_rms'])} rms "
            f"({span('fault_mmf_a_rms')}); at the fit {d['mu']:.1%} of its turns through "
            f"{d['R_f_ohm']:.3g} ohm" + ("" if searched else " (the parameters' bridge)")
            + f", {d['fault_current_a_rms']:.3g} A rms in the fault loop, "
            f"{d['fault_power_w']:.3g} W in the bridge")
    loose = [q for q in ("mu", "R_f_ohm", "fault_current_a_rms", "fault_power_w")
             if q not in det]
    if loose:
        text += ("; fits as good span " + ", ".join(f"{_WORDS[q][0]} {span(q)}" for q in loose)
                 + ": not determined by the fit (the shorted fraction and the fault "
                 "resistance trade off)")
    if d.get("open"):
        text += (" and reach the end of the resistances searched ("
                 + " and ".join(d["open"]) + ")")
    return text


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
                 hypothesis=hypothesis, refit_from_healthy=False, measure=measure,
                 extra_grids=GRIDS,
                 k_components=(2, 3, 4), indicators=INDICATORS)
