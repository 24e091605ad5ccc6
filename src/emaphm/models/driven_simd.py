"""The recorded-voltage model's kernel laid out for SIMD: the population in vector lanes.

:func:`_kernel` here has the signature and the semantics of
:func:`emaphm.models.driven._kernel` and runs the same period
(:func:`emaphm.models.driven._period`'s physics: the winding driven by the applied voltages
and the change of the flux linkage, the mechanics as a predictor of the measured angle),
laid out as :mod:`emaphm.models.monitoring_simd` lays out the monitoring model: one scratch
array ``B (n_blk, N_ROWS, LANES)`` holds every candidate's constants and state as rows of
``LANES`` doubles, the stages loop over blocks and lanes with only scalars crossing into
the inlined physics, and no branch stays a branch (LLVM's selects). The sines and cosines
are the measured angle's, computed once for every candidate (libm's) and rotated by each
lane's encoder offset and eccentricity phase,
the Stribeck exponential :func:`~emaphm.models.mechanics.stribeck_factor` (branch-free by
design);
the scalar kernel on libm's sines agrees to round-off (tested).
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import cached_njit
from ._monitoring_common import I_DIVERGED
from .controller import CTL_DELAY, N_CTL
from .driven import MECH_SUBSTEPS, N_RES, flux_coefficients, rotate
from .driven import _kernel as scalar_kernel
from .inverter import dead_time_drop
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_DELTA, C_ECC, C_ECC_PHASE, C_FDJ,
                     C_FSJ, C_GAMMA, C_GAMMA_END, C_MU_A, C_MU_B, C_MU_C, C_OMEGA_S, C_PHI,
                     C_PHI_END, C_T0, C_V_DT, N_CP, P_CTL, P_C_L, P_C_M, P_D_C, P_J_L, P_J_M, P_K_C,
                     P_POLES, P_T_S)
from .pmsm import phase_currents, torque_loops
from .step import (current_loop_inline, inline, inlined, lane_reader, llvm_select as select,
                   vector_reader,
                   phase_currents_inline, torque_loops_inline, transmission_step_inline,
                   winding_input_inline, winding_step_inline)
from .mechanics import stribeck_factor
from .windings import Q

__all__ = ["_kernel", "LANES", "run", "SCALAR_TAIL"]

kernel_jit = cached_njit(nogil=True, error_model="numpy")

#: Candidates per block: one AVX-512 register of doubles (two AVX2 ones).
LANES = 8

# rows of B: the candidate's constants (its CP row), then its state
R_C = 0
(R_Z0, R_Z1, R_Z2, R_Z3, R_Z4, R_IA, R_IB, R_IC, R_THM, R_WM, R_THL, R_WL, R_TQ, R_LA, R_LB,
 R_LC, R_SE, R_SM, R_ALIVE, R_NA, R_NB, R_NC, R_CA, R_CB, R_CC, R_TQ1, R_FD,
 R_SPD, R_CPD, R_SGD, R_CGD, R_UA, R_UB, R_UC, R_INT_D, R_INT_Q, R_VA1, R_VB1,
 R_VC1) = range(N_CP, N_CP + 39)
N_ROWS = R_VC1 + 1

_lane_c = lane_reader(N_CP, "lane_c_driven")
_read_ctl = vector_reader(N_CTL, "read_ctl_driven_simd")

_dead_time_drop = inlined(dead_time_drop)
_flux = inlined(flux_coefficients)
_rotate = inlined(rotate)
_stribeck = inlined(stribeck_factor)


@inline
def _residual_stage(B, k, i_meas_k, theta_k, w_e_k, w_m_k, scale, l_1, l_2):
    """Each lane's residuals at sample k into its sums, then the observer's correction."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            ra = B[b, R_IA, l] - i_meas_k[0]
            rb = B[b, R_IB, l] - i_meas_k[1]
            rc = B[b, R_IC, l] - i_meas_k[2]
            thm = B[b, R_THM, l]
            rm = scale * (thm - theta_k)
            B[b, R_SE, l] += w_e_k[0] * ra * ra + w_e_k[1] * rb * rb + w_e_k[2] * rc * rc
            B[b, R_SM, l] += w_m_k * rm * rm
            e = theta_k - thm
            B[b, R_THM, l] = thm + l_1 * e
            B[b, R_WM, l] += l_2 * e


@inline
def _flux_stage(B, theta1, trig1, p):
    """Each lane's flux linkage and back-EMF coefficients at the next measured angle (its
    sines ``trig1`` rotated by the lane's encoder offset and eccentricity phase)."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            c = _lane_c(B, R_C, b, l)
            s, co = _rotate(trig1[0], trig1[1], B[b, R_SPD, l], B[b, R_CPD, l])
            sg, cg = _rotate(trig1[2], trig1[3], B[b, R_SGD, l], B[b, R_CGD, l])
            na, nb, nc, ca, cb, cc = _flux(s, co, sg, cg, theta1 + c[C_DELTA], p, c[C_C0_A],
                                           c[C_C0_B], c[C_C0_C], c[C_ECC])
            B[b, R_NA, l] = na
            B[b, R_NB, l] = nb
            B[b, R_NC, l] = nc
            B[b, R_CA, l] = ca
            B[b, R_CB, l] = cb
            B[b, R_CC, l] = cc


@inline
def _command_stage(B, u):
    """Each lane's voltages of the period: the recorded ones ``u``."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            B[b, R_UA, l] = u[0]
            B[b, R_UB, l] = u[1]
            B[b, R_UC, l] = u[2]


@inline
def _current_loop_stage(B, i_ref, omega, s_e, c_e, ctl, delayed):
    """Each lane's voltages of the period from the drive's current loop on its own currents
    towards the recorded references ``i_ref`` (at the measured angle's ``s_e, c_e`` and
    speed ``omega``): those computed now, or under a delay those of the period before."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            va, vb, vc, int_d, int_q = current_loop_inline(
                i_ref[0], i_ref[1], B[b, R_IA, l], B[b, R_IB, l], B[b, R_IC, l], omega, s_e,
                c_e, B[b, R_INT_D, l], B[b, R_INT_Q, l], ctl)
            B[b, R_INT_D, l] = int_d
            B[b, R_INT_Q, l] = int_q
            B[b, R_UA, l] = select(delayed, B[b, R_VA1, l], va)
            B[b, R_UB, l] = select(delayed, B[b, R_VB1, l], vb)
            B[b, R_UC, l] = select(delayed, B[b, R_VC1, l], vc)
            B[b, R_VA1, l] = va
            B[b, R_VB1, l] = vb
            B[b, R_VC1, l] = vc


@inline
def _winding_stage(B, i_meas1, T_s, inv_i_0):
    """Each lane's winding over the period (driven by its voltages of the period) and the
    torque at its end."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            c = _lane_c(B, R_C, b, l)
            V = max(c[C_V_DT], 0.0)
            mu_a, mu_b, mu_c = c[C_MU_A], c[C_MU_B], c[C_MU_C]
            w0, w1, w2, w3, w4 = winding_input_inline(
                B[b, R_UA, l] - _dead_time_drop(B[b, R_IA, l], V, inv_i_0),
                B[b, R_UB, l] - _dead_time_drop(B[b, R_IB, l], V, inv_i_0),
                B[b, R_UC, l] - _dead_time_drop(B[b, R_IC, l], V, inv_i_0),
                (B[b, R_NA, l] - B[b, R_LA, l]) / T_s, (B[b, R_NB, l] - B[b, R_LB, l]) / T_s,
                (B[b, R_NC, l] - B[b, R_LC, l]) / T_s, mu_a, mu_b, mu_c)
            z0, z1, z2, z3, z4 = winding_step_inline(
                B[b, R_Z0, l], B[b, R_Z1, l], B[b, R_Z2, l], B[b, R_Z3, l], B[b, R_Z4, l],
                w0, w1, w2, w3, w4, c[C_PHI:C_PHI_END], c[C_GAMMA:C_GAMMA_END])
            ja, jb, jc = phase_currents_inline(z0, z1)
            B[b, R_Z0, l] = z0
            B[b, R_Z1, l] = z1
            B[b, R_Z2, l] = z2
            B[b, R_Z3, l] = z3
            B[b, R_Z4, l] = z4
            B[b, R_IA, l] = ja
            B[b, R_IB, l] = jb
            B[b, R_IC, l] = jc
            B[b, R_TQ1, l] = torque_loops_inline(i_meas1[0], i_meas1[1], i_meas1[2], z2, z3, z4,
                                           B[b, R_CA, l], B[b, R_CB, l], B[b, R_CC, l],
                                           mu_a, mu_b, mu_c)
            B[b, R_LA, l] = B[b, R_NA, l]
            B[b, R_LB, l] = B[b, R_NB, l]
            B[b, R_LC, l] = B[b, R_NC, l]


@inline
def _friction_stage(B):
    """Each lane's sliding friction at the period's start speed (the Stribeck drop)."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            FSJ, FDJ = B[b, R_C + C_FSJ, l], B[b, R_C + C_FDJ, l]
            B[b, R_FD, l] = FDJ + (FSJ - FDJ) * _stribeck(B[b, R_WM, l],
                                                          max(B[b, R_C + C_OMEGA_S, l], 0.0))


@inline
def _mech_stage(B, frac, T_l, mech):
    """One step of each lane's mechanics on the torque ``frac`` of the way through the
    period."""
    J_m, C_m, J_l, C_l, K_c, D_c, h = mech
    for b in range(B.shape[0]):
        for l in range(LANES):
            c = _lane_c(B, R_C, b, l)
            T_m = B[b, R_TQ, l] + frac * (B[b, R_TQ1, l] - B[b, R_TQ, l])
            thm, wm, thl, wl = transmission_step_inline(
                B[b, R_THM, l], B[b, R_WM, l], B[b, R_THL, l], B[b, R_WL, l], T_m,
                T_l + c[C_T0], J_m, C_m, c[C_FSJ], B[b, R_FD, l], J_l, C_l, c[C_BACKLASH],
                K_c, D_c, h)
            B[b, R_THM, l] = thm
            B[b, R_WM, l] = wm
            B[b, R_THL, l] = thl
            B[b, R_WL, l] = wl


@inline
def _commit_stage(B):
    """The period's torque kept; a lane that left the physical range frozen, its sums inf."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            B[b, R_TQ, l] = B[b, R_TQ1, l]
            ok = ((B[b, R_ALIVE, l] != 0.0) & (abs(B[b, R_IA, l]) < I_DIVERGED)
                  & (abs(B[b, R_IB, l]) < I_DIVERGED) & (abs(B[b, R_IC, l]) < I_DIVERGED)
                  & (abs(B[b, R_WM, l]) < 1e5) & (abs(B[b, R_THM, l]) < 1e9))
            B[b, R_ALIVE, l] = select(ok, 1.0, 0.0)
            B[b, R_SE, l] = select(ok, B[b, R_SE, l], np.inf)
            B[b, R_SM, l] = select(ok, B[b, R_SM, l], np.inf)


@inline
def _output_stage(B, k, n_pop, keep_r, keep_t, i_meas, theta, w_e, w_m, scale, residuals,
                  out_i, out_f, out_theta, out_torque):
    """Each candidate's residuals at sample k (weighted, as the sums) and its traces, where
    asked."""
    sw = (math.sqrt(w_e[k, 0]), math.sqrt(w_e[k, 1]), math.sqrt(w_e[k, 2]), math.sqrt(w_m[k]))
    for j in range(n_pop):
        b = j // LANES
        l = j - b * LANES
        if keep_r:
            residuals[j, k, 0] = sw[0] * (B[b, R_IA, l] - i_meas[k, 0])
            residuals[j, k, 1] = sw[1] * (B[b, R_IB, l] - i_meas[k, 1])
            residuals[j, k, 2] = sw[2] * (B[b, R_IC, l] - i_meas[k, 2])
            residuals[j, k, 3] = sw[3] * (scale * (B[b, R_THM, l] - theta[k]))
        if keep_t:
            out_i[j, k, 0] = B[b, R_IA, l]
            out_i[j, k, 1] = B[b, R_IB, l]
            out_i[j, k, 2] = B[b, R_IC, l]
            out_f[j, k, 0] = B[b, R_Z2, l]
            out_f[j, k, 1] = B[b, R_Z3, l]
            out_f[j, k, 2] = B[b, R_Z4, l]
            out_theta[j, k] = B[b, R_THM, l]
            out_torque[j, k] = B[b, R_TQ, l]


@kernel_jit
def _kernel(P, CP, observer, u, i_ref, omega, theta, trig, omega0, i_meas, T_load, w_e, w_m,
            i_0, sse, residuals, out_i, out_f, out_theta, out_torque, status):
    """Drop-in for :func:`emaphm.models.driven._kernel` (same arguments, same results to
    round-off)."""
    n_pop = CP.shape[0]
    n = theta.shape[0]
    for j in range(n_pop):
        sse[j, 0] = 0.0
        sse[j, 1] = 0.0
        status[j] = 0
    if n_pop == 0:
        return
    keep_r = residuals.shape[0] == n_pop
    keep_t = out_i.shape[0] == n_pop
    p = P[P_POLES]
    T_s = P[P_T_S]
    mech = (P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L], P[P_K_C], P[P_D_C], T_s / MECH_SUBSTEPS)
    l_1, l_2, scale = observer[0], observer[1], observer[2]
    inv_i_0 = 1.0 / i_0
    closed = i_ref.shape[0] == n
    ctl = _read_ctl(P, P_CTL)
    delayed = P[P_CTL + CTL_DELAY] != 0.0
    n_blk = (n_pop + LANES - 1) // LANES
    B = np.zeros((n_blk, N_ROWS, LANES))
    # the winding from the first measured currents, the observer at the first angle and speed
    y0 = Q[0, 0] * i_meas[0, 0] + Q[1, 0] * i_meas[0, 1] + Q[2, 0] * i_meas[0, 2]
    y1 = Q[1, 1] * i_meas[0, 1] + Q[2, 1] * i_meas[0, 2]
    ia0, ib0, ic0 = phase_currents(y0, y1)
    for b in range(n_blk):
        for l in range(LANES):
            j = min(b * LANES + l, n_pop - 1)     # padding lanes repeat the last candidate
            for e in range(N_CP):
                B[b, R_C + e, l] = CP[j, e]
            B[b, R_Z0, l] = y0
            B[b, R_Z1, l] = y1
            B[b, R_IA, l] = ia0
            B[b, R_IB, l] = ib0
            B[b, R_IC, l] = ic0
            B[b, R_THM, l] = theta[0]
            B[b, R_WM, l] = omega0
            B[b, R_THL, l] = theta[0]
            B[b, R_WL, l] = omega0
            B[b, R_ALIVE, l] = 1.0
            d = CP[j, C_DELTA]
            B[b, R_SPD, l] = math.sin(p * d)
            B[b, R_CPD, l] = math.cos(p * d)
            B[b, R_SGD, l] = math.sin(d + CP[j, C_ECC_PHASE])
            B[b, R_CGD, l] = math.cos(d + CP[j, C_ECC_PHASE])
    _flux_stage(B, theta[0], (trig[0, 0], trig[0, 1], trig[0, 2], trig[0, 3]), p)
    for b in range(n_blk):
        for l in range(LANES):
            B[b, R_LA, l] = B[b, R_NA, l]
            B[b, R_LB, l] = B[b, R_NB, l]
            B[b, R_LC, l] = B[b, R_NC, l]
            B[b, R_TQ, l] = torque_loops(i_meas[0, 0], i_meas[0, 1], i_meas[0, 2], 0.0, 0.0,
                                         0.0, B[b, R_CA, l], B[b, R_CB, l], B[b, R_CC, l],
                                         B[b, R_C + C_MU_A, l], B[b, R_C + C_MU_B, l],
                                         B[b, R_C + C_MU_C, l])
    for k in range(n):
        if keep_r or keep_t:
            _output_stage(B, k, n_pop, keep_r, keep_t, i_meas, theta, w_e, w_m, scale,
                          residuals, out_i, out_f, out_theta, out_torque)
        _residual_stage(B, k, (i_meas[k, 0], i_meas[k, 1], i_meas[k, 2]), theta[k],
                        (w_e[k, 0], w_e[k, 1], w_e[k, 2]), w_m[k], scale, l_1, l_2)
        if k == n - 1:
            break
        _flux_stage(B, theta[k + 1], (trig[k + 1, 0], trig[k + 1, 1], trig[k + 1, 2],
                                      trig[k + 1, 3]), p)
        if closed:
            _current_loop_stage(B, (i_ref[k, 0], i_ref[k, 1]), omega[k], trig[k, 0], trig[k, 1],
                                ctl, delayed)
        else:
            _command_stage(B, (u[k, 0], u[k, 1], u[k, 2]))
        _winding_stage(B, (i_meas[k + 1, 0], i_meas[k + 1, 1], i_meas[k + 1, 2]), T_s, inv_i_0)
        _friction_stage(B)
        for s in range(MECH_SUBSTEPS):
            _mech_stage(B, (s + 0.5) / MECH_SUBSTEPS, T_load[k], mech)
        _commit_stage(B)
    for j in range(n_pop):
        b = j // LANES
        l = j - b * LANES
        sse[j, 0] = B[b, R_SE, l]
        sse[j, 1] = B[b, R_SM, l]
        if B[b, R_ALIVE, l] == 0.0 or not (np.isfinite(sse[j, 0]) and np.isfinite(sse[j, 1])):
            sse[j, 0] = np.inf
            sse[j, 1] = np.inf
            status[j] = 1


#: Candidates left over after the SIMD kernel's full blocks that run in the scalar kernel
#: instead (as :data:`emaphm.models.monitoring.SCALAR_TAIL`).
SCALAR_TAIL = 1


def run(P, CP, observer, u, theta, trig, omega0, i_meas, T_load, w_e, w_m, i_0, *,
        i_ref=None, omega=None, residuals=False, traces=False, kernel="simd"):
    """The kernels with the outputs allocated: ``(sse (n_pop, 2), status, extra)`` where
    ``extra`` holds ``"residuals"`` and/or ``"i_abc", "f_abc", "theta_m", "torque"`` as
    asked. ``kernel``: ``"simd"`` (:func:`_kernel`, full blocks of lanes, a lone remainder in
    the scalar kernel) or ``"scalar"`` (:func:`emaphm.models.driven._kernel`, one candidate
    after another: the readable reference the lanes are tested against). ``i_ref (n, 2)``
    and ``omega (n,)``: the drive's recorded current references and the measured speed,
    which its current loop turns into each candidate's voltages instead of ``u``."""
    n_pop, n = CP.shape[0], theta.shape[0]
    if i_ref is None:
        i_ref, omega = np.zeros((0, 2)), np.zeros(0)
    sse = np.zeros((n_pop, 2))
    status = np.zeros(n_pop, dtype=np.int64)
    r = np.empty((n_pop, n, N_RES) if residuals else (0, 0, N_RES))
    shape = (n_pop, n) if traces else (0, 0)
    out_i, out_f = np.zeros(shape + (3,)), np.zeros(shape + (3,))
    out_th, out_tq = np.zeros(shape), np.zeros(shape)
    parts = [(slice(0, n_pop), scalar_kernel)]
    if kernel == "simd":
        tail = n_pop % LANES
        split = n_pop - tail if tail <= SCALAR_TAIL else n_pop
        parts = [(slice(0, split), _kernel), (slice(split, n_pop), scalar_kernel)]
    for rows, kern in parts:
        if rows.stop > rows.start:
            kern(P, CP[rows], observer, u, i_ref, omega, theta, trig, float(omega0), i_meas,
                 T_load, w_e, w_m,
                 float(i_0), sse[rows], r[rows] if residuals else r, out_i[rows] if traces else out_i,
                 out_f[rows] if traces else out_f, out_th[rows] if traces else out_th,
                 out_tq[rows] if traces else out_tq, status[rows])
    extra = {}
    if residuals:
        extra["residuals"] = r
    if traces:
        extra.update(i_abc=out_i, f_abc=out_f, theta_m=out_th, torque=out_tq)
    return sse, status, extra
