"""A high-resistance connection of one phase: a loose or corroded terminal, crimp or
connector raising that phase's resistance by a factor (a common PMSM fault; it heats the
joint, which oxidises further).

Searched beside k as the relative deviations of the three phases' resistances
(``"R_a"``, ``"R_b"``, ``"R_c"``, :data:`emaphm.models.layout.NUISANCE_PARAMETERS`) in a
refit the verdict makes when the residual asks (:func:`hypothesis`):

* on the recorded-voltage path (the drive's voltage commands in the trace): there the
  winding's ``v = R i + L di/dt + e`` is seen directly, and a phase 30 % up leaves a
  residual of a fifth of the currents' noise-free fit (fit ratio 0.3 -> 1.7 on the preset),
  inside the misfit test's acceptance: no other symptom asks for it;
* on the other paths where the fit is a misfit: there the drive's current loop takes up
  most of a phase's resistance (about 7 mA rms at +30 % on the preset), and only a large
  one leaves a trace (``emaphm assess`` found none up to 1.5x on either actuator).

Either way the refit is made only where a screen of seven evaluations (each phase's
resistance 10 % up and down from the fit, :func:`screened_gain`) promises it a gain: 8 ms,
where a refit costs 0.3-0.7 s; measured on the recorded-voltage path, a phase at 1.3x
promises 0.2, healthy units, friction and a weaker magnet 0.002, a 10 % short 0.04 (its
refit runs beside the short's own, which explains it better).

It is told from the common resistance (the winding's temperature, searched as ``"R"``
after a calibration) by being on one phase: the fault's measure is the *imbalance*, each
phase's deviation above the median of the three; and from an inter-turn short, which
lowers a phase's impedance and drives a fault loop, by the refit that explains the
residual better (a short's own refit searches the fault bridge).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Mapping

from .base import PHASES, Fault, FaultMode, Indicator, Injection, Reading, searched_values

__all__ = ["MODE", "hypothesis", "imbalance"]

#: The searched names, one per phase.
NAMES = tuple(f"R_{p.lower()}" for p in PHASES)


def _deviations(extra: Mapping[str, Any]) -> tuple[list[float], float] | None:
    """The three phases' relative resistance deviations searched beside k and their
    median; None where they were not searched."""
    try:
        dev = [float(extra[n]) for n in NAMES]
    except (KeyError, TypeError, ValueError):
        return None
    return dev, sorted(dev)[1]


def imbalance(extra: Mapping[str, Any]) -> tuple[float, ...] | None:
    """Each phase's resistance deviation above the median of the three (relative), from
    the values searched beside k; None where they were not searched."""
    found = _deviations(extra)
    if found is None:
        return None
    dev, mid = found
    return tuple(d - mid for d in dev)


def read(r: Reading) -> list[Fault]:
    found = _deviations(r.extra)
    if found is None:
        return []
    dev, mid = found
    j = max(range(3), key=lambda i: dev[i])
    if not dev[j] - mid > r.thresholds.resistance:
        return []
    ph = PHASES[j]
    R = r.params.motor.R[j]
    factor = (1.0 + dev[j]) / (1.0 + mid)
    return [Fault("resistance", NAMES[j], dev[j] - mid, dev[j] - mid,
                  f"high-resistance connection in phase {ph}: its resistance {factor:.2f}x the "
                  f"other phases' ({R * factor * 1e3:.0f} mohm where the winding has "
                  f"{R * 1e3:.0f} mohm): a loose or corroded terminal, crimp or connector",
                  phase=ph, details={"resistance_factor": factor})]


#: The step of the screen's probes (relative resistance of one phase).
SCREEN_STEP = 0.1

#: The screen asks for the refit where its parabolas promise to lower the fit by this share
#: at least: a third of the gain a refit must show to be kept
#: (:data:`emaphm.verdict.HYPOTHESIS_GAIN`), the parabola being a local model.
SCREEN_GAIN = 0.01


def screened_gain(problem: Any, ident: Any) -> float:
    """What a refit of one phase's resistance may gain, from one batch of seven
    evaluations: the fit at the identified k and its parameters, and with each phase's
    resistance ``+-SCREEN_STEP``; a parabola through each phase's three gives the least
    fit along it. The relative gain of the best phase (0 where none curves upward)."""
    import numpy as np

    names = _searched(problem)
    own = names[:-len(NAMES)]
    nu = getattr(ident, "nuisance", {}) or {}
    row = np.concatenate([np.asarray(ident.k, dtype=float), [float(nu.get(n, 0.0)) for n in own],
                          np.zeros(3)])
    K = np.tile(row, (7, 1))
    for j in range(3):
        K[1 + 2 * j, len(row) - 3 + j] = SCREEN_STEP
        K[2 + 2 * j, len(row) - 3 + j] = -SCREEN_STEP
    trial = replace(problem, nuisance=names, start=None, search=None, objective=None)
    f = np.asarray(trial.objective(K), dtype=float)
    f0 = f[0]
    if not np.all(np.isfinite(f)) or not f0 > 0:
        return 1.0                    # cannot tell: let the refit decide
    best = 0.0
    for j in range(3):
        fp, fm = f[1 + 2 * j], f[2 + 2 * j]
        curv = fp + fm - 2.0 * f0
        if curv > 0:
            best = max(best, (fp - fm) ** 2 / (8.0 * curv * f0))
    return float(best)


def hypothesis(problem: Any, ident: Any, diag: Any) -> tuple[str, ...] | None:
    """The three phases' resistances searched beside the problem's own parameters, where
    the screen (:func:`screened_gain`) promises a gain: on the recorded-voltage path, where
    the resistance is seen directly; elsewhere only when the fit is a misfit."""
    from ..firmware import RECORDED_VOLTAGES

    misfit = diag.unexplained is not None and diag.unexplained.reason == "misfit"
    if problem.drive_model != RECORDED_VOLTAGES and not misfit:
        return None
    if screened_gain(problem, ident) < SCREEN_GAIN:
        return None
    return _searched(problem)


def _searched(problem: Any) -> tuple[str, ...]:
    """The problem's own parameters beside k, then the three phases' resistances."""
    return tuple(n for n in problem.nuisance if n not in NAMES) + NAMES


def inject(severity: float, phase: str | None = "A") -> Injection:
    """Phase ``phase``'s resistance ``severity`` x its own (1 to 5)."""
    if not 1.0 <= severity <= 5.0:
        raise ValueError(f"a connection's resistance is 1 to 5 x the phase's, got {severity:g}")
    j = PHASES.index((phase or "A").upper())

    def plant(params):
        R = list(params.motor.R)
        R[j] = R[j] * float(severity)
        return replace(params, motor=replace(params.motor, R=tuple(R)))

    return Injection(plant=plant)


def measure(r: Reading) -> dict[str, float]:
    """The largest phase's imbalance, what ``read`` compares with its threshold (0 where
    the resistances were not searched)."""
    up = imbalance(r.extra)
    return {"resistance": 0.0 if up is None else max(up)}


def reading(phase: int):
    def read_one(diagnosis: Mapping[str, Any], extra: Mapping[str, Any]) -> float | None:
        for nu in searched_values(diagnosis, extra):
            up = imbalance(nu)
            if up is not None:
                return up[phase]
        return None
    return read_one


#: Trended by each phase's imbalance (``resistance_a`` to ``_c``), where a refit searched
#: the three resistances. Failure at 0.5: the phase's resistance 1.5x the others', its
#: joint dissipating 1.5x the winding's share of the copper losses in a few milliohms,
#: the point where a connection's temperature runs away (oxidation raising the resistance
#: further) and the torque ripple of the unbalanced currents grows. Model discrepancy 0.046:
#: the relative RMS error of the imbalance read against the plant's on recorded-voltage
#: plant traces of calibrated production units at 1.2x, 1.3x and 1.5x (mean -0.005, 48
#: readings, both actuators, unit seeds 80000-80007, apart from the assessment's units).
INDICATORS = tuple(Indicator(f"resistance_{p.lower()}", f"connection resistance {p}",
                             failure=0.5, discrepancy=0.046, bounds=(-0.5, 4.0), phase=p,
                             reading=reading(j),
                             unmeasured="the verdict searched no phase resistance: it does "
                                        "on traces with the drive's voltage commands, and "
                                        "elsewhere where the fit is a misfit")
                   for j, p in enumerate(PHASES))

MODE = FaultMode("resistance", "high-resistance connection", threshold=0.1, read=read,
                 inject=inject, severity_unit="x the phase's resistance",
                 grid=(1.1, 1.2, 1.3, 1.5), per_phase=True, spec="PHASE:FACTOR",
                 hypothesis=hypothesis, measure=measure,
                 magnitude=lambda s: abs(s - 1.0), indicators=INDICATORS)
