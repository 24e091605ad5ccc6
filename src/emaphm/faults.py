"""The fault vector ``k`` (top-level parameters, Eq. 1 of the paper) and its
mapping onto the physical parameters, plus the paper's named scenarios.

=====  ======================  =========================================================
k      fault                   mapping (paper Table 1, Eq. 2, design notes)
=====  ======================  =========================================================
k1     dry friction            FSJ, FDJ x (1 + 2 k1)            (x3 at k1 = 1)
k2     backlash                backlash x (1 + 99 k2)           (x100 at k2 = 1)
k3     short circuit, phase a  R_a x (1 - s), L_a x (1 - s)^2, c0_a x (1 - s), s = k3
k4     short circuit, phase b  same on phase b
k5     short circuit, phase c  same on phase c
k6     eccentricity modulus    Eq. 2 modulus
k7     eccentricity phase      Eq. 2 phase = 2 pi (k7 - 0.5)    (-180..180 deg)
k8     proportional gain       Kp x (0.5 + k8)                  (0.5x..1.5x)
=====  ======================  =========================================================

Two **fault models** map k3..k5 (``fault_model``, :data:`FAULT_MODELS`):

* ``"paper"``: the paper's turn removal above, ``R x (1 - s)``, ``L x (1 - s)^2``,
  ``c0 x (1 - s)``: the shorted turns simply vanish from the phase;
* ``"physical"``: an inter-turn short circuit as it happens: ``s`` is the
  fraction ``Motor.mu`` of the phase's turns bridged by the fault resistance
  ``Motor.R_f``, and a fault-loop current flows through them
  (:mod:`emaphm.models.windings`). R, L and c0 keep their healthy values.

The paper's scenarios keep the paper's fault model; ``turn-short-*`` are
physical scenarios of realistic size (:data:`SCENARIO_FAULT_MODELS`).

Nominal is ``[0, 0, 0, 0, 0, 0, 0.5, 0.5]``. The shorted fraction ``s`` is
capped at :data:`MAX_SHORTED_FRACTION` so that a phase keeps a finite, non-zero
inductance (a fully shorted winding is no RL branch any more).

The scale functions below take scalars or NumPy arrays alike, so the single
mapping :func:`apply_faults` and the population packing of the monitoring
model share the same formulas.
"""

from __future__ import annotations

from dataclasses import replace
from types import MappingProxyType
from typing import Mapping, Sequence

import numpy as np

from ._text import shown
from .params import ActuatorParams

__all__ = [
    "loop_report",
    "N_K",
    "K_NAMES",
    "K_LABELS",
    "K_NOMINAL",
    "K_LOWER",
    "K_UPPER",
    "MAX_SHORTED_FRACTION",
    "FaultVectorError",
    "as_k",
    "friction_scale",
    "backlash_scale",
    "shorted_fraction",
    "eccentricity_phase",
    "gain_scale",
    "apply_faults",
    "FAULT_MODELS",
    "check_fault_model",
    "SCENARIOS",
    "SCENARIO_FAULT_MODELS",
    "PAPER_SCENARIOS",
    "scenario_fault_model",
    "scenario",
    "error_pct",
]

N_K = 8
K_NAMES = ("friction", "backlash", "short_a", "short_b", "short_c",
           "ecc_modulus", "ecc_phase", "gain")
K_LABELS = ("dry friction", "backlash", "short circuit, phase A", "short circuit, phase B",
            "short circuit, phase C", "eccentricity modulus", "eccentricity phase",
            "proportional gain drift")
K_NOMINAL = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5])
K_NOMINAL.setflags(write=False)
K_LOWER = np.zeros(N_K)
K_UPPER = np.ones(N_K)
K_LOWER.setflags(write=False)
K_UPPER.setflags(write=False)

#: Largest shorted fraction of a phase's turns the models accept.
MAX_SHORTED_FRACTION = 0.99


class FaultVectorError(ValueError):
    """A fault vector has the wrong length, is not finite or leaves [0, 1]."""


def as_k(k: Sequence[float] | np.ndarray | str) -> np.ndarray:
    """Validate and return ``k`` as a float64 array of shape (8,).

    Accepts a sequence or a comma-separated string such as ``"0.75,0,0,0,0,0,0.5,0.5"``.
    """
    if isinstance(k, str):
        try:
            k = [float(x) for x in k.replace(" ", "").split(",") if x != ""]
        except ValueError:
            raise FaultVectorError(
                f"fault vector {shown(k)} is not a comma-separated list of 8 numbers, "
                "e.g. 0.75,0,0,0,0,0,0.5,0.5") from None
    arr = np.asarray(k, dtype=float)
    if arr.shape != (N_K,):
        raise FaultVectorError(
            f"fault vector needs {N_K} components ({', '.join(K_NAMES)}), got shape "
            f"{arr.shape}; nominal is 0,0,0,0,0,0,0.5,0.5")
    if not np.all(np.isfinite(arr)):
        raise FaultVectorError(f"fault vector has non-finite components: {arr.tolist()}")
    bad = np.flatnonzero((arr < 0.0) | (arr > 1.0))
    if bad.size:
        i = int(bad[0])
        raise FaultVectorError(
            f"fault vector component k{i + 1} ({K_NAMES[i]}) = {arr[i]:g} is outside [0, 1]")
    return arr


def friction_scale(k1):
    """Dry friction multiplier: 1 at k1 = 0, 3 at k1 = 1."""
    return 1.0 + 2.0 * k1


def backlash_scale(k2):
    """Backlash width multiplier: 1 at k2 = 0, 100 at k2 = 1."""
    return 1.0 + 99.0 * k2


#: The backlash width [rad] that k2 = 1 reaches on a transmission whose data sheet states
#: none (``backlash = 0``: a harmonic or a direct drive), where a multiple of nothing would
#: say nothing: the preset's nominal 0.2 mrad x 100, so k2 keeps its scale there.
BACKLASH_FROM_ZERO = 0.02


def backlash_width(nominal, k2):
    """The backlash width [rad] of ``k2`` on a transmission of ``nominal`` width [rad]:
    ``nominal x backlash_scale(k2)``, or ``BACKLASH_FROM_ZERO k2`` where the nominal
    width is zero."""
    nominal = np.asarray(nominal, dtype=float)
    return np.where(nominal > 0.0, nominal * backlash_scale(k2), BACKLASH_FROM_ZERO * np.asarray(k2))


def shorted_fraction(k_sc):
    """Fraction of a phase's turns shorted, capped at MAX_SHORTED_FRACTION."""
    return np.minimum(k_sc, MAX_SHORTED_FRACTION)


def loop_report(mean_square, R_f, mu) -> dict[str, list[float]]:
    """Each phase's fault loop from the mean square of its current ``mean_square`` [A^2],
    its bridge ``R_f`` [ohm] and its shorted fraction ``mu``: ``fault_current_a_rms``,
    ``fault_power_w`` (``R_f i_f^2``, what heats the insulation), ``fault_mmf_a_rms``
    (the loop's ampere-turns per turn of the phase, ``mu i_f`` rms: what the terminal
    currents see, so what a mild short's fit pins while ``mu`` and ``R_f`` trade off) and
    ``R_f_ohm``."""
    ms = np.asarray(mean_square, dtype=float)
    R_f = np.asarray(R_f, dtype=float)
    rms = np.sqrt(ms)
    return {"fault_current_a_rms": [float(x) for x in rms],
            "fault_power_w": [float(x) for x in R_f * ms],
            "fault_mmf_a_rms": [float(x) for x in np.asarray(mu, dtype=float) * rms],
            "R_f_ohm": [float(x) for x in R_f]}


def eccentricity_phase(k7):
    """Eccentricity phase of Eq. 2 in rad: -pi at k7 = 0, 0 at 0.5, +pi at 1."""
    return 2.0 * np.pi * (k7 - 0.5)


def gain_scale(k8):
    """Position proportional gain multiplier: 0.5 at k8 = 0, 1 at 0.5, 1.5 at 1."""
    return 0.5 + k8


#: The mappings of k3..k5: the paper's turn removal, or a physical fault loop.
FAULT_MODELS = ("paper", "physical")


def check_fault_model(name: str) -> str:
    """``name`` if it is one of :data:`FAULT_MODELS`, else a FaultVectorError naming them."""
    if name not in FAULT_MODELS:
        raise FaultVectorError(f"unknown fault model {shown(name)}; choose 'physical' (the shorted "
                               "turns carry a fault-loop current) or 'paper' (the shorted turns "
                               "are removed: R x (1-k), L x (1-k)^2)")
    return name


def apply_faults(params: ActuatorParams, k: Sequence[float] | np.ndarray,
                 fault_model: str = "paper") -> ActuatorParams:
    """Map nominal parameters and a fault vector onto faulty parameters (pure).

    ``params`` describes the healthy actuator (its eccentricity must be zero);
    the result carries the short circuits (per-phase R, L, c0 under
    ``fault_model="paper"``; the shorted fractions ``Motor.mu`` under
    ``"physical"``), the eccentricity of Eq. 2, the scaled friction, backlash
    and proportional gain.
    """
    kk = as_k(k)
    check_fault_model(fault_model)
    m, tr, ctl = params.motor, params.transmission, params.controller
    s = shorted_fraction(kk[2:5])
    if fault_model == "paper":
        R = tuple(float(r * (1.0 - si)) for r, si in zip(m.R, s))
        L = tuple(float(ell * (1.0 - si) ** 2) for ell, si in zip(m.L, s))
        c0 = tuple(float(c * (1.0 - si)) for c, si in zip(m.c0, s))
        motor = replace(m, R=R, L=L, c0=c0)
    else:
        motor = replace(m, mu=tuple(float(si) for si in s))
    motor = replace(motor, ecc=float(kk[5]), ecc_phase=float(eccentricity_phase(kk[6])))
    fs = float(friction_scale(kk[0]))
    trans = replace(tr, FSJ=tr.FSJ * fs, FDJ=tr.FDJ * fs,
                    backlash=float(backlash_width(tr.backlash, kk[1])))
    # the drive's data-sheet settings stay the healthy motor's
    ctrl = replace(ctl.kept_for(m, params.load, motor, params.load),
                   Kp=ctl.Kp * float(gain_scale(kk[7])))
    return replace(params, motor=motor, transmission=trans, controller=ctrl)


def _single(index: int, value: float) -> np.ndarray:
    k = K_NOMINAL.copy()
    k[index] = value
    k.setflags(write=False)
    return k


def _scenarios() -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {"nominal": K_NOMINAL}
    for mode, idx in (("friction", 0), ("backlash", 1), ("short-circuit", 2),
                      ("eccentricity", 5)):
        out[f"{mode}-low"] = _single(idx, 0.25)
        out[f"{mode}-high"] = _single(idx, 0.75)
    # k8 = 0.25 and 0.75 around the nominal 0.5: a gain 25 % low and 25 % high
    out["gain-low"] = _single(7, 0.25)
    out["gain-high"] = _single(7, 0.75)
    multiple = np.array([0.0133, 0.05, 0.003, 0.0, 0.0, 0.012, 0.5, 0.35])  # paper Eq. 8
    multiple.setflags(write=False)
    out["multiple"] = multiple
    # physical inter-turn short circuits of realistic size: 5 % and 15 % of phase A's turns
    out["turn-short-5pct"] = _single(2, 0.05)
    out["turn-short-15pct"] = _single(2, 0.15)
    return out


#: The paper's scenarios (section 3.2 and 4) plus ``nominal`` and the physical
#: ``turn-short-*`` ones: name -> k.
SCENARIOS: Mapping[str, np.ndarray] = MappingProxyType(_scenarios())

#: The paper's 11 fault scenarios (5 modes x 2 magnitudes, and the multiple faults).
PAPER_SCENARIOS = tuple(n for n in SCENARIOS if n != "nominal" and not n.startswith("turn-short"))

#: The fault model each scenario is defined under: the paper's keep the paper's turn
#: removal (so the paper campaign keeps its meaning), ``turn-short-*`` are physical.
SCENARIO_FAULT_MODELS: Mapping[str, str] = MappingProxyType(
    {name: ("physical" if name.startswith("turn-short") else "paper") for name in SCENARIOS})


def scenario(name: str) -> np.ndarray:
    """The fault vector of a named scenario (a copy)."""
    try:
        return SCENARIOS[name].copy()
    except KeyError:
        raise FaultVectorError(
            f"unknown scenario {shown(name)}; choose one of {', '.join(SCENARIOS)} "
            "(`emaphm scenarios` lists them with their k)") from None


def scenario_fault_model(name: str) -> str:
    """The fault model a named scenario is defined under."""
    scenario(name)
    return SCENARIO_FAULT_MODELS[name]


def error_pct(k, k_true) -> float:
    """Identification error of Eq. 9 in percent.

    ``100/sqrt(6.5) * sqrt(sum_{i=1..6} (k_i - k_i,true)^2
    + k6_true (k7 - k7_true)^2 + (k8 - k8_true)^2)``: the eccentricity phase
    counts only as much as there is eccentricity to see. The phase is an angle
    (k7 = 0 and 1 are both 180 deg), so its difference is taken the short way
    round, within [-0.5, 0.5).
    """
    k = np.asarray(k, dtype=float)
    kt = np.asarray(k_true, dtype=float)
    d = k - kt
    d7 = (d[..., 6] + 0.5) % 1.0 - 0.5
    s = np.sum(d[..., :6] ** 2, axis=-1) + kt[..., 5] * d7 ** 2 + d[..., 7] ** 2
    return 100.0 / np.sqrt(6.5) * np.sqrt(s)
