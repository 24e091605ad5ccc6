"""The monitoring model's kernel laid out for SIMD: the population runs in vector lanes.

:func:`_kernel` here has the signature and the semantics of
:func:`emaphm.models.monitoring._kernel` and runs the same step
(:mod:`emaphm.models.step`: :func:`~emaphm.models.step.control` and
:func:`~emaphm.models.step.substep`, inlined), on :func:`~emaphm.models.step.sincos`;
the scalar kernel on the same sines gives the same bits (tested). It is laid out so
that LLVM's loop vectoriser turns the loop over candidates into packed AVX2/AVX-512
code:

* **one contiguous scratch array** ``B (n_blk, N_ROWS, LANES)`` holds, per
  block of ``LANES`` candidates, every per-candidate parameter and state
  variable as a row of ``LANES`` doubles (array-of-structures-of-arrays). The
  vectorised loops touch this array only, at row offsets that are compile-time
  constants, so the vectoriser needs no runtime alias checks; the inputs
  ``theta_ref, T_load, i_target, weights`` are read into scalars before the
  loops and the outputs are written by short copy loops after them;
* **no branches that stay branches**: the scalar physics functions
  (:func:`~emaphm.models.controller.control_step` with its PI steps,
  :func:`~emaphm.models.inverter.modulate`, the winding circuit's
  :func:`~emaphm.models.pmsm.winding_input`, :func:`~emaphm.models.pmsm.winding_step`,
  :func:`~emaphm.models.pmsm.phase_currents`, :func:`~emaphm.models.pmsm.torque_loops`,
  :func:`~emaphm.models.mechanics.transmission_step` with Borello's
  :func:`~emaphm.models.mechanics.friction_step`) are reused as they are, their
  own code recompiled for Numba-IR inlining (``inline="always"``) with IEEE
  division; LLVM if-converts their ``if``s (anti-windup, saturations, voltage
  limit, stick/slip, backlash contact) to selects, evaluating both sides and
  picking one, which computes the same value. The kernel's own choices
  (overcurrent trip, eccentricity, divergence freeze, sine quadrant) use
  :func:`select`, an LLVM ``select``; the divergence check freezes a candidate
  with a mask instead of ``continue``;
* **only scalars cross into the inlined functions**: the lane loops load from
  and store to ``B`` themselves (an array handed to an inlined function leaves
  an NRT incref/decref pair, two calls, in the loop body); the 5 x 5 matrices
  ``Phi, Gamma`` of the winding step travel as tuples of 25 scalars, loaded
  row by row at constant offsets;
* **sine and cosine without libm**: :func:`~emaphm.models.step.sincos` is fdlibm's
  (Cody-Waite reduction by pi/2 in three rounds, ``__kernel_sin``/``__kernel_cos``
  polynomials, quadrant by selects): within 1 ulp of the correctly rounded
  result like libm's, so the two differ by an ulp now and then, which is the
  only difference from the scalar kernel on libm. Past ``|x| > TRIG_LIMIT`` (where the
  three-part reduction loses accuracy; only a runaway candidate gets there) a
  scalar fix-up loop recomputes the value with ``math.sin``/``math.cos``.

Stages per control period, each a loop over blocks and lanes (the lane loop
vectorised): trig [+ rare scalar fix-up], controller, first sub-step,
[trig + sub-step]*, traces (scalar copy, only when stored), divergence check
and commit. The time loop is outermost, so the blocks of a stage are
independent work for the out-of-order core.

The kernel is cached on disk under a digest of the model sources
(:mod:`emaphm.models._jit`), so an edit to a physics module it inlines compiles it
afresh (Numba's own cache would not see it).
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import cached_njit
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_ECC, C_ECC_PHASE, C_FDJ, C_FSJ,
                     C_GAMMA, C_KP, C_MU_A, C_PHI, C_T0, P_C_L, P_C_M, P_I_MAX, P_I_TRIP, P_D_C, P_J_L, P_J_M, P_K_C,
                     P_K_T, P_KD, P_KI, P_KI_I, P_KI_W, P_KP_I, P_KP_W, P_OMEGA_MAX, P_POLES,
                     P_T_MAX, P_T_S, P_THETA0, P_V_DC)
from ._monitoring_common import STATUS_DIVERGED, STATUS_OK, STATUS_TRIPPED, _check_step
from .step import (TRIG_LIMIT, control_inline, healthy_inline, inline, llvm_select as select,
                   sincos_inline as sincos, substep_inline)

#: The kernel: IEEE division (``error_model="numpy"``), as a ZeroDivisionError check on
#: every ``/`` is an early exit from the lane loop that the vectoriser cannot handle. For a
#: physical ``P`` no division in the loop has a zero divisor; ``CP[:, C_KP] == 0`` (divides
#: in the back-calculation) gives inf/nan, so a diverged candidate, where the scalar kernel
#: raises ZeroDivisionError.
kernel_jit = cached_njit(nogil=True, error_model="numpy")

__all__ = ["_kernel", "LANES", "TRIG_LIMIT"]

#: Candidates per block: one AVX-512 register of doubles (two AVX2 ones).
LANES = 8


# ---- rows of the scratch array B[block, row, lane] -------------------------------------

# per-candidate parameters; the winding step's Phi and Gamma row by row (25 rows each)
(R_KP, R_FSJ, R_FDJ, R_BACKLASH, R_C0A, R_C0B, R_C0C, R_ECC, R_ECCPH,
 R_MUA, R_MUB, R_MUC) = range(12)
R_PHI = 12
R_GAM = R_PHI + 25
# committed state (start of the control period): the winding circuit's z = [y, f] with
# i_abc = Q y alongside; R_TRIP, R_ALIVE: 1.0 or 0.0
(R_THM, R_WM, R_THL, R_WL, R_IA, R_IB, R_IC, R_Z0, R_Z1, R_Z2, R_Z3, R_Z4,
 R_E0, R_E1, R_E2, R_E3, R_TRIP, R_FIT, R_ALIVE) = range(R_GAM + 25, R_GAM + 44)
# working state (during the control period), in the same order as the committed rows
(W_THM, W_WM, W_THL, W_WL, W_IA, W_IB, W_IC, W_Z0, W_Z1, W_Z2, W_Z3, W_Z4,
 W_E0, W_E1, W_E2, W_E3, W_TRIP, W_FIT) = range(R_ALIVE + 1, R_ALIVE + 19)
# per-period intermediates: leg voltages, sines and cosines, torque at the control instant
(R_UA, R_UB, R_UC, R_SE, R_CE, R_SG, R_CG, R_TQ) = range(W_FIT + 1, W_FIT + 9)
# the candidate's constant load torque beside the profile's (layout's C_T0)
R_T0 = R_TQ + 1
N_ROWS = R_T0 + 1
N_STATE = 18      # rows R_THM..R_FIT and W_THM..W_FIT


@inline
def _trig(thm, ecc_phase, p):
    """Sines and cosines of ``p theta_m`` and ``theta_m + ecc_phase``; True if out of range."""
    x = p * thm
    g = thm + ecc_phase
    s_e, c_e = sincos(x)
    s_g, c_g = sincos(g)
    return s_e, c_e, s_g, c_g, (abs(x) > TRIG_LIMIT) | (abs(g) > TRIG_LIMIT)


# The stages loop over blocks and lanes; the lane loop is the one that vectorises. Its body
# loads from and stores to ``B`` itself and calls only the scalar functions above: an array
# passed into an inlined function leaves an NRT incref/decref pair (calls) in the loop.

@inline
def _trig_stage(B, p):
    """Sines and cosines of every lane (vector), libm for a runaway lane (scalar, rare)."""
    big = False
    for b in range(B.shape[0]):
        for l in range(LANES):
            s_e, c_e, s_g, c_g, out = _trig(B[b, W_THM, l], B[b, R_ECCPH, l], p)
            B[b, R_SE, l] = s_e
            B[b, R_CE, l] = c_e
            B[b, R_SG, l] = s_g
            B[b, R_CG, l] = c_g
            big |= out
    if big:
        for b in range(B.shape[0]):
            for l in range(LANES):
                x = p * B[b, W_THM, l]
                g = B[b, W_THM, l] + B[b, R_ECCPH, l]
                if abs(x) > TRIG_LIMIT:
                    B[b, R_SE, l] = math.sin(x)
                    B[b, R_CE, l] = math.cos(x)
                if abs(g) > TRIG_LIMIT:
                    B[b, R_SG, l] = math.sin(g)
                    B[b, R_CG, l] = math.cos(g)


@inline
def _plant_stage(B, first, mech):
    """One sub-step of every lane (vector); the first also keeps the torque for the traces."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            # the winding step's matrices, row-major, as tuples of scalars
            Phi = (B[b, R_PHI + 0, l], B[b, R_PHI + 1, l], B[b, R_PHI + 2, l], B[b, R_PHI + 3, l],
                   B[b, R_PHI + 4, l], B[b, R_PHI + 5, l], B[b, R_PHI + 6, l], B[b, R_PHI + 7, l],
                   B[b, R_PHI + 8, l], B[b, R_PHI + 9, l], B[b, R_PHI + 10, l],
                   B[b, R_PHI + 11, l], B[b, R_PHI + 12, l], B[b, R_PHI + 13, l],
                   B[b, R_PHI + 14, l], B[b, R_PHI + 15, l], B[b, R_PHI + 16, l],
                   B[b, R_PHI + 17, l], B[b, R_PHI + 18, l], B[b, R_PHI + 19, l],
                   B[b, R_PHI + 20, l], B[b, R_PHI + 21, l], B[b, R_PHI + 22, l],
                   B[b, R_PHI + 23, l], B[b, R_PHI + 24, l])
            Gam = (B[b, R_GAM + 0, l], B[b, R_GAM + 1, l], B[b, R_GAM + 2, l], B[b, R_GAM + 3, l],
                   B[b, R_GAM + 4, l], B[b, R_GAM + 5, l], B[b, R_GAM + 6, l], B[b, R_GAM + 7, l],
                   B[b, R_GAM + 8, l], B[b, R_GAM + 9, l], B[b, R_GAM + 10, l],
                   B[b, R_GAM + 11, l], B[b, R_GAM + 12, l], B[b, R_GAM + 13, l],
                   B[b, R_GAM + 14, l], B[b, R_GAM + 15, l], B[b, R_GAM + 16, l],
                   B[b, R_GAM + 17, l], B[b, R_GAM + 18, l], B[b, R_GAM + 19, l],
                   B[b, R_GAM + 20, l], B[b, R_GAM + 21, l], B[b, R_GAM + 22, l],
                   B[b, R_GAM + 23, l], B[b, R_GAM + 24, l])
            thm, wm, thl, wl, z0, z1, z2, z3, z4, ia, ib, ic, tq = substep_inline(
                B[b, W_THM, l], B[b, W_WM, l], B[b, W_THL, l], B[b, W_WL, l],
                B[b, W_Z0, l], B[b, W_Z1, l], B[b, W_Z2, l], B[b, W_Z3, l], B[b, W_Z4, l],
                B[b, W_IA, l], B[b, W_IB, l], B[b, W_IC, l],
                B[b, R_SE, l], B[b, R_CE, l], B[b, R_SG, l], B[b, R_CG, l],
                B[b, R_UA, l], B[b, R_UB, l], B[b, R_UC, l],
                (B[b, R_C0A, l], B[b, R_C0B, l], B[b, R_C0C, l]), B[b, R_ECC, l],
                (B[b, R_MUA, l], B[b, R_MUB, l], B[b, R_MUC, l]), Phi, Gam,
                B[b, R_FSJ, l], B[b, R_FDJ, l], B[b, R_BACKLASH, l], B[b, R_T0, l], mech)
            B[b, W_THM, l] = thm
            B[b, W_WM, l] = wm
            B[b, W_THL, l] = thl
            B[b, W_WL, l] = wl
            B[b, W_Z0, l] = z0
            B[b, W_Z1, l] = z1
            B[b, W_Z2, l] = z2
            B[b, W_Z3, l] = z3
            B[b, W_Z4, l] = z4
            B[b, W_IA, l] = ia
            B[b, W_IB, l] = ib
            B[b, W_IC, l] = ic
            if first:
                B[b, R_TQ, l] = tq


@inline
def _control_stage(B, period, ctl):
    """Fitness term, trip, controller and modulation of every lane (vector)."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            fit, trip, e0, e1, e2, e3, u_a, u_b, u_c = control_inline(
                B[b, W_THM, l], B[b, W_WM, l], B[b, W_IA, l], B[b, W_IB, l], B[b, W_IC, l],
                B[b, R_SE, l], B[b, R_CE, l], B[b, W_TRIP, l], B[b, W_FIT, l],
                B[b, W_E0, l], B[b, W_E1, l], B[b, W_E2, l], B[b, W_E3, l], B[b, R_KP, l],
                period, ctl)
            B[b, W_FIT, l] = fit
            B[b, W_TRIP, l] = trip
            B[b, W_E0, l] = e0
            B[b, W_E1, l] = e1
            B[b, W_E2, l] = e2
            B[b, W_E3, l] = e3
            B[b, R_UA, l] = u_a
            B[b, R_UB, l] = u_b
            B[b, R_UC, l] = u_c


@inline
def _commit_stage(B):
    """Divergence check (vector): keep the period's state, or freeze the lane at its last
    good state with infinite fitness (the scalar kernel's ``status``/``continue``)."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            ok = (B[b, R_ALIVE, l] != 0.0) & healthy_inline(
                B[b, W_IA, l], B[b, W_IB, l], B[b, W_IC, l], B[b, W_WM, l], B[b, W_THM, l])
            for r in range(N_STATE - 1):
                x = select(ok, B[b, W_THM + r, l], B[b, R_THM + r, l])
                B[b, R_THM + r, l] = x
                B[b, W_THM + r, l] = x
            f = select(ok, B[b, W_FIT, l], np.inf)
            B[b, R_FIT, l] = f
            B[b, W_FIT, l] = f
            B[b, R_ALIVE, l] = select(ok, 1.0, 0.0)


@kernel_jit
def _kernel(P, CP, theta_ref, T_load, n_sub, i_target, weights,
            out_i, out_theta, out_omega, out_torque, fitness, status):
    """Drop-in for :func:`emaphm.models.monitoring._kernel` (same arguments, same results).

    Shapes: ``P (N_P,)``, ``CP (n_pop, N_CP)``, ``theta_ref, T_load (n,)``;
    ``i_target, weights (n, 3)`` or ``(0, 3)`` for no fitness; ``out_i
    (n_pop, n, 3)``, ``out_theta, out_omega, out_torque (n_pop, n)`` or
    zero-sized for no traces; ``fitness, status (n_pop,)`` written in place.
    ``P, CP`` must be packed for ``n_sub`` (ValueError otherwise).
    """
    _check_step(P, n_sub)
    n_pop = CP.shape[0]
    n = theta_ref.shape[0]
    store = out_i.shape[0] == n_pop and n_pop > 0
    with_fit = i_target.shape[0] == n
    for j in range(n_pop):
        fitness[j] = 0.0
        status[j] = STATUS_OK
    if n_pop == 0:
        return
    p = P[P_POLES]
    T_s = P[P_T_S]
    dt = T_s / n_sub
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    K_c, D_c = P[P_K_C], P[P_D_C]
    V_dc = P[P_V_DC]
    Ki, Kd, omega_max, Kp_w, Ki_w = P[P_KI], P[P_KD], P[P_OMEGA_MAX], P[P_KP_W], P[P_KI_W]
    T_max, k_T, I_max, Kp_i, Ki_i = P[P_T_MAX], P[P_K_T], P[P_I_MAX], P[P_KP_I], P[P_KI_I]
    I_trip = P[P_I_TRIP]
    ctl = (Ki, Kd, omega_max, Kp_w, Ki_w, T_max, k_T, I_max, Kp_i, Ki_i, V_dc, T_s, I_trip)
    theta0 = P[P_THETA0]
    n_blk = (n_pop + LANES - 1) // LANES
    B = np.zeros((n_blk, N_ROWS, LANES))
    for b in range(n_blk):
        for l in range(LANES):
            # padding lanes repeat the last candidate; their results are not written out
            j = min(b * LANES + l, n_pop - 1)
            B[b, R_KP, l] = CP[j, C_KP]
            B[b, R_FSJ, l] = CP[j, C_FSJ]
            B[b, R_FDJ, l] = CP[j, C_FDJ]
            B[b, R_BACKLASH, l] = CP[j, C_BACKLASH]
            B[b, R_C0A, l] = CP[j, C_C0_A]
            B[b, R_C0B, l] = CP[j, C_C0_B]
            B[b, R_C0C, l] = CP[j, C_C0_C]
            B[b, R_ECC, l] = CP[j, C_ECC]
            B[b, R_ECCPH, l] = CP[j, C_ECC_PHASE]
            B[b, R_T0, l] = CP[j, C_T0]
            for ph in range(3):
                B[b, R_MUA + ph, l] = CP[j, C_MU_A + ph]
            for e in range(25):
                B[b, R_PHI + e, l] = CP[j, C_PHI + e]
                B[b, R_GAM + e, l] = CP[j, C_GAMMA + e]
            B[b, R_THM, l] = theta0
            B[b, R_THL, l] = theta0
            B[b, W_THM, l] = theta0
            B[b, W_THL, l] = theta0
            B[b, R_ALIVE, l] = 1.0
    ta = tb = tc = wa = wb = wc = 0.0
    for k in range(n):
        ref = theta_ref[k]
        T_l = T_load[k]
        if with_fit:
            ta, tb, tc = i_target[k, 0], i_target[k, 1], i_target[k, 2]
            wa, wb, wc = weights[k, 0], weights[k, 1], weights[k, 2]
        _trig_stage(B, p)
        _control_stage(B, (ta, tb, tc, wa, wb, wc, ref), ctl)
        mech = (T_l, J_m, C_m, J_l, C_l, K_c, D_c, dt)
        _plant_stage(B, True, mech)
        for s in range(1, n_sub):
            _trig_stage(B, p)
            _plant_stage(B, False, mech)
        if store:
            for j in range(n_pop):
                b = j // LANES
                l = j - b * LANES
                if B[b, R_ALIVE, l] != 0.0:
                    out_i[j, k, 0] = B[b, R_IA, l]
                    out_i[j, k, 1] = B[b, R_IB, l]
                    out_i[j, k, 2] = B[b, R_IC, l]
                    out_theta[j, k] = B[b, R_THM, l]
                    out_omega[j, k] = B[b, R_WM, l]
                    out_torque[j, k] = B[b, R_TQ, l]
        _commit_stage(B)
    for j in range(n_pop):
        b = j // LANES
        l = j - b * LANES
        fitness[j] = B[b, R_FIT, l]
        if B[b, R_ALIVE, l] == 0.0:
            status[j] = STATUS_DIVERGED
        elif B[b, R_TRIP, l] != 0.0:
            status[j] = STATUS_TRIPPED
