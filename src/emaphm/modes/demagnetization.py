"""A partially demagnetized rotor: the magnet flux down on every phase alike.

The back-EMF coefficient (= the torque constant) of every phase drops by the same factor;
the drive keeps its data-sheet ``k_T``, so the currents grow to give the torque the
command needs. Searched beside k as the parameter ``"demag"`` (the flux's relative
deviation over the losses of a demagnetized rotor, :data:`emaphm.search.NUISANCE_RANGE`),
in place of the narrow ``"flux"`` drift, when the residual asks for it
(:func:`hypothesis`): the fit is a misfit, or the flux drift searched after a
calibration sits at its lower bound. It is told from a short (one phase) by being the
same on all three, and from the unit's own tolerance by its threshold: after
``emaphm calibrate`` a loss beyond ``thresholds.demagnetization`` against the calibrated
flux (temperature moves a magnet's flux by a few percent); on a data sheet, beyond that
plus the flux tolerance of the production units (:data:`emaphm.units.DEFAULT_TOLERANCES`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Mapping

from .base import Fault, FaultMode, Indicator, Injection, Reading, searched_values

__all__ = ["MODE", "hypothesis", "tolerance", "flux_loss"]

#: The flux drift searched after a calibration (``"flux"``) sitting this close to its
#: lower bound asks for the demagnetization hypothesis.
AT_BOUND = 0.005


def tolerance(params: Any) -> float:
    """The flux deviation a healthy unit of ``params`` may have: 0 for a calibrated unit
    (its own flux is known), the production tolerance for a data sheet."""
    if params is not None and params.calibration.date:
        return 0.0
    from ..units import DEFAULT_TOLERANCES

    return float(-DEFAULT_TOLERANCES.flux[0])


def read(r: Reading) -> list[Fault]:
    dev = r.extra.get("demag", r.extra.get("flux"))
    if dev is None:
        return []
    loss = -float(dev)
    if not loss > r.thresholds.demagnetization + tolerance(r.params):
        return []
    ratio = 1.0 - loss
    c0 = r.params.motor.c0[0]
    return [Fault("demagnetization", "demag" if "demag" in r.extra else "flux", float(dev), loss,
                  f"magnets demagnetized: flux {100 * ratio:.1f}% of the "
                  f"{'calibrated unit' if r.params.calibration.date else 'data sheet'} "
                  f"(back-EMF coefficient {c0 * ratio:.4g} V s/rad instead of {c0:.4g})",
                  details={"flux_ratio": ratio})]


def hypothesis(problem: Any, ident: Any, diag: Any) -> tuple[str, ...] | None:
    """The parameters to search beside k for a demagnetized rotor, when the residual asks:
    the problem's own with the flux drift ``"flux"`` replaced by ``"demag"`` (and the
    winding resistance beside it)."""
    flux = ident.nuisance.get("flux")
    at_bound = flux is not None and flux <= -0.06 + AT_BOUND
    misfit = diag.unexplained is not None and diag.unexplained.reason == "misfit"
    if not (at_bound or misfit):
        return None
    names = [n for n in problem.nuisance if n != "flux"]
    if "R" not in names:
        names.insert(0, "R")
    return tuple(names) + ("demag",)


def inject(severity: float, phase: str | None = None) -> Injection:
    """A rotor that lost the fraction ``severity`` (0 to 0.5) of its magnet flux."""
    if not 0.0 <= severity <= 0.5:
        raise ValueError(f"a demagnetization loses 0 to 0.5 of the flux, got {severity:g}")

    def plant(params):
        m = params.motor
        return replace(params, motor=replace(m, c0=tuple(c * (1.0 - severity) for c in m.c0)))

    return Injection(plant=plant)


#: Threshold 8 % of flux lost, against the calibrated unit: above the drift of its magnets'
#: temperature, which the identification searches as ``"flux"`` within +-6 % (see
#: docs/fault-modes.md for how it was set); on a data sheet plus the production tolerance.
def measure(r: Reading) -> dict[str, float]:
    """The flux loss beyond the unit's tolerance, what ``read`` compares with its threshold."""
    dev = r.extra.get("demag", r.extra.get("flux"))
    loss = 0.0 if dev is None else -float(dev)
    return {"demagnetization": loss - tolerance(r.params)}


def flux_loss(diagnosis: Mapping[str, Any] | None, extra: Mapping[str, Any] | None) -> float | None:
    """The fraction of the magnet flux lost, as an inspection measured it: from the refit the
    verdict was read on where it searched the flux (``"demag"``, or the drift ``"flux"``),
    else from the identification's own flux drift (searched at every inspection of a
    calibrated unit, within +-6 %); None where neither searched it (a data sheet's unit
    whose residual did not ask for the hypothesis: its flux differs from the data sheet by
    the production tolerance, which no loss can be told from)."""
    for nu in searched_values(diagnosis or {}, extra or {}):
        for name in ("demag", "flux"):
            if nu.get(name) is not None:
                return -float(nu[name])
    return None


#: Trended by the fraction of the flux lost (:func:`flux_loss`), against the calibrated
#: unit (on a data sheet, where the refit measured it, against the data sheet). Failure at
#: 0.2: the drive needs 1/0.8 = 1.25x the current for the same torque, 1.56x the copper
#: losses, at the edge of a flight actuator's torque and thermal margins, and the larger
#: current's own field demagnetizes the magnets further. Model discrepancy 0.035: the
#: relative RMS error of the loss read against the plant's, at the inspections where it is
#: at least a quarter of the threshold, on reference-plant traces of production units
#: calibrated first, the flux lost linearly (``benchmarks/bench_demagnetization.py
#: --tune-discrepancy 12``, seeds 100-111, apart from the reported 0-19): 0.025 (mean
#: -0.020, 36 readings) on the preset, 0.035 (mean -0.031, 33 readings) on ema-270v-750w;
#: the larger is kept.
INDICATORS = (Indicator("demagnetization", "demagnetization (flux lost)", failure=0.2,
                        discrepancy=0.035, bounds=(-0.5, 1.0), reading=flux_loss,
                        unmeasured="their identification searched no magnet flux: a data "
                                   "sheet's unit, whose residual did not ask for a "
                                   "demagnetization; after emaphm calibrate every inspection "
                                   "measures it"),)

MODE = FaultMode("demagnetization", "demagnetized rotor", threshold=0.08, read=read,
                 inject=inject, severity_unit="fraction of the magnet flux lost",
                 grid=(0.05, 0.1, 0.15, 0.25), hypothesis=hypothesis, measure=measure,
                 indicators=INDICATORS)
