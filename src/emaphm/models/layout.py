"""Flat float64 layouts of the parameters, as the compiled kernels take them.

``P`` holds what every candidate shares (the drive and the healthy parts);
``CP`` holds one row per candidate with what the fault vector changes. Both
the reference model (one faulty actuator) and the monitoring model (a
population of candidate ``k``) are fed through these, so a candidate's row
built from ``(nominal, k)`` by :func:`pack_population` equals the row of
:func:`pack` applied to ``apply_faults(nominal, k)``.
"""

from __future__ import annotations

import numpy as np

from ..faults import (as_k, backlash_scale, eccentricity_phase, friction_scale, gain_scale,
                      shorted_fraction, N_K)
from ..params import ActuatorParams

# shared parameters P[...]
(P_POLES, P_J_M, P_C_M, P_T_MAX, P_I_MAX, P_V_DC, P_T_S, P_KP_I, P_KI_I, P_KI, P_KD,
 P_OMEGA_MAX, P_KP_W, P_KI_W, P_K_T, P_J_L, P_C_L, P_THETA0, P_I_TRIP) = range(19)
N_P = 19

# per-candidate parameters CP[:, ...]
(C_KP, C_FSJ, C_FDJ, C_BACKLASH, C_R_A, C_R_B, C_R_C, C_L_A, C_L_B, C_L_C,
 C_C0_A, C_C0_B, C_C0_C, C_ECC, C_ECC_PHASE) = range(15)
N_CP = 15


def pack_shared(params: ActuatorParams, theta0: float = 0.0) -> np.ndarray:
    """The shared parameter vector P; ``theta0`` [rad] is the initial motor
    (and load) angle, at rest (a recorded trace need not start at zero)."""
    m, inv, ctl, load = params.motor, params.inverter, params.controller, params.load
    P = np.empty(N_P)
    P[P_POLES] = m.p
    P[P_J_M] = m.J_m
    P[P_C_M] = m.C_m
    P[P_T_MAX] = m.T_max
    P[P_I_MAX] = m.I_max
    P[P_V_DC] = inv.V_dc
    P[P_T_S] = inv.T_s
    P[P_KP_I] = inv.Kp_i
    P[P_KI_I] = inv.Ki_i
    P[P_KI] = ctl.Ki
    P[P_KD] = ctl.Kd
    P[P_OMEGA_MAX] = ctl.omega_max
    P[P_KP_W] = ctl.Kp_w
    P[P_KI_W] = ctl.Ki_w
    P[P_K_T] = ctl.k_T
    P[P_J_L] = load.J_l
    P[P_C_L] = load.C_l
    P[P_THETA0] = theta0
    P[P_I_TRIP] = inv.I_trip
    return P


def pack(params: ActuatorParams, theta0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(P, CP)`` for one actuator as it is (faults already applied); CP has one row."""
    m, tr, ctl = params.motor, params.transmission, params.controller
    row = np.empty(N_CP)
    row[C_KP] = ctl.Kp
    row[C_FSJ] = tr.FSJ
    row[C_FDJ] = tr.FDJ
    row[C_BACKLASH] = tr.backlash
    row[C_R_A:C_R_C + 1] = m.R
    row[C_L_A:C_L_C + 1] = m.L
    row[C_C0_A:C_C0_C + 1] = m.c0
    row[C_ECC] = m.ecc
    row[C_ECC_PHASE] = m.ecc_phase
    return pack_shared(params, theta0), row[None, :]


def pack_population(nominal: ActuatorParams, K: np.ndarray,
                    theta0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(P, CP)`` for a population of fault vectors ``K`` (n_pop, 8) on a healthy actuator.

    Rows of K are not range-checked here (the optimizers keep them in the box);
    use :func:`emaphm.faults.as_k` for user input.
    """
    K = np.atleast_2d(np.asarray(K, dtype=float))
    if K.ndim != 2 or K.shape[1] != N_K:
        raise ValueError(f"population of fault vectors must have shape (n_pop, {N_K}), got {K.shape}")
    P, base = pack(nominal, theta0)
    CP = np.repeat(base, K.shape[0], axis=0)
    CP[:, C_KP] *= gain_scale(K[:, 7])
    fs = friction_scale(K[:, 0])
    CP[:, C_FSJ] *= fs
    CP[:, C_FDJ] *= fs
    CP[:, C_BACKLASH] *= backlash_scale(K[:, 1])
    s = shorted_fraction(K[:, 2:5])
    CP[:, C_R_A:C_R_C + 1] *= 1.0 - s
    CP[:, C_L_A:C_L_C + 1] *= (1.0 - s) ** 2
    CP[:, C_C0_A:C_C0_C + 1] *= 1.0 - s
    CP[:, C_ECC] = K[:, 5]
    CP[:, C_ECC_PHASE] = eccentricity_phase(K[:, 6])
    return P, CP


__all__ = ["pack", "pack_shared", "pack_population", "N_P", "N_CP", "as_k"]
