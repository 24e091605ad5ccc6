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

from ._jit import cached_njit, variants
from .compiling import wait_for
from .controller import N_CTL, feedforward
from .layout import (C_ECC_PHASE, N_CP, P_C_L, P_C_M, P_CTL, P_D_C, P_INV_I0, P_I_TRIP,
                     P_J_L, P_J_M, P_K_C, P_POLES, P_T_S, P_THETA0)
from ._monitoring_common import (STATUS_DIVERGED, STATUS_OK, STATUS_TRIPPED, _check_step,
                                 variant_key)
from .step import (N_Q, N_X, TRIG_LIMIT, control_inline, control_plain_inline, healthy_inline,
                   substep_ideal_inline,
                   initial_x_inline, inline, inlined, lane_reader, lane_writer, llvm_select as select,
                   sincos_inline as sincos, substep_inline, vector_reader)

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

#: the candidate's constants: its CP row, column for column (the layout's C_* + R_C)
R_C = 0
#: committed state (start of the control period): the plant's x and the drive's q
#: (:data:`~emaphm.models.step.X_FIELDS`, :data:`~emaphm.models.step.Q_FIELDS`), then
#: R_ALIVE (1.0 or 0.0)
R_X = R_C + N_CP
R_Q = R_X + N_X
R_ALIVE = R_Q + N_Q
#: working state (during the control period), in the same order as the committed rows
W_X = R_ALIVE + 1
W_Q = W_X + N_X
#: per-period intermediates: leg voltages, sines and cosines, torque at the control instant
(R_UA, R_UB, R_UC, R_SE, R_CE, R_SG, R_CG, R_TQ) = range(W_Q + N_Q, W_Q + N_Q + 8)
N_ROWS = R_TQ + 1
N_STATE = N_X + N_Q      # rows R_X.. and W_X.. of the state, committed and working
#: the Eq. 4 sum and the trip flag, rows of the drive's state
Q_TRIP, Q_FIT = 0, 1

_lane_c = lane_reader(N_CP, "lane_c")
_lane_x = lane_reader(N_X, "lane_x")
_lane_q = lane_reader(N_Q, "lane_q")
_put_x = lane_writer(N_X, "put_x")
_put_q = lane_writer(N_Q, "put_q")
#: a drive without options keeps only the trip, the sum and the integrals of its state: the
#: rest (filters, held voltages) are what the options' helpers read
N_Q_PLAIN = 2 + 4
_put_q_plain = lane_writer(N_Q_PLAIN, "put_q_plain")
_read_ctl = vector_reader(N_CTL, "read_ctl")


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
            s_e, c_e, s_g, c_g, out = _trig(B[b, W_X, l], B[b, R_C + C_ECC_PHASE, l], p)
            B[b, R_SE, l] = s_e
            B[b, R_CE, l] = c_e
            B[b, R_SG, l] = s_g
            B[b, R_CG, l] = c_g
            big |= out
    if big:
        for b in range(B.shape[0]):
            for l in range(LANES):
                x = p * B[b, W_X, l]
                g = B[b, W_X, l] + B[b, R_C + C_ECC_PHASE, l]
                if abs(x) > TRIG_LIMIT:
                    B[b, R_SE, l] = math.sin(x)
                    B[b, R_CE, l] = math.cos(x)
                if abs(g) > TRIG_LIMIT:
                    B[b, R_SG, l] = math.sin(g)
                    B[b, R_CG, l] = math.cos(g)


def _plant_stage(B, first, mech):
    """One sub-step of every lane (vector); the first also keeps the torque for the traces."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            x, tq = substep_inline(_lane_x(B, W_X, b, l), _lane_c(B, R_C, b, l), mech,
                                   B[b, R_SE, l], B[b, R_CE, l], B[b, R_SG, l], B[b, R_CG, l],
                                   B[b, R_UA, l], B[b, R_UB, l], B[b, R_UC, l])
            _put_x(B, W_X, b, l, x)
            if first:
                B[b, R_TQ, l] = tq


#: the sub-step of an inverter with dead time, and of one without (the same numbers)
_plant_stage_ideal = inlined(_plant_stage, substep_inline=substep_ideal_inline)
_plant_stage = inlined(_plant_stage, substep_inline=substep_inline)


def _control_stage(B, ctl, I_trip, period):
    """Fitness term, trip, controller and modulation of every lane (vector)."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            q, u_a, u_b, u_c = control_inline(_lane_x(B, W_X, b, l), _lane_q(B, W_Q, b, l),
                                              _lane_c(B, R_C, b, l), ctl, I_trip, period,
                                              B[b, R_SE, l], B[b, R_CE, l])
            _put_q(B, W_Q, b, l, q)
            B[b, R_UA, l] = u_a
            B[b, R_UB, l] = u_b
            B[b, R_UC, l] = u_c


#: the stage of a drive with options, and of one without (the same numbers, less work)
_control_stage_plain = inlined(_control_stage, control_inline=control_plain_inline,
                               _put_q=_put_q_plain)
_control_stage = inlined(_control_stage, control_inline=control_inline)


def _commit_stage(B):
    """Divergence check (vector): keep the period's state, or freeze the lane at its last
    good state with infinite fitness (the scalar kernel's ``status``/``continue``)."""
    for b in range(B.shape[0]):
        for l in range(LANES):
            ok = (B[b, R_ALIVE, l] != 0.0) & healthy_inline(
                B[b, W_X + 9, l], B[b, W_X + 10, l], B[b, W_X + 11, l], B[b, W_X + 1, l],
                B[b, W_X, l])
            for r in range(N_STATE):
                x = select(ok, B[b, W_X + r, l], B[b, R_X + r, l])
                B[b, R_X + r, l] = x
                B[b, W_X + r, l] = x
            f = select(ok, B[b, W_Q + Q_FIT, l], np.inf)
            B[b, R_Q + Q_FIT, l] = f
            B[b, W_Q + Q_FIT, l] = f
            B[b, R_ALIVE, l] = select(ok, 1.0, 0.0)


#: the commit of a drive with options, and of one without (the head of its state: the rest
#: stays zero)
_commit_stage_plain = inlined(_commit_stage, N_STATE=N_X + N_Q_PLAIN)
_commit_stage = inlined(_commit_stage)


def _kernel(P, CP, theta_ref, T_load, n_sub, i_target, weights,
            out_i, out_theta, out_omega, out_torque, fitness, status, out_f):
    """Drop-in for :func:`emaphm.models.monitoring._kernel` (same arguments, same results;
    ``out_f``, the fault loops' currents, is not written: ask the scalar kernel).

    Shapes: ``P (N_P,)``, ``CP (n_pop, N_CP)``, ``theta_ref, T_load (n,)``;
    ``i_target, weights (n, 3)`` or ``(0, 3)`` for no fitness; ``out_i
    (n_pop, n, 3)``, ``out_theta, out_omega, out_torque (n_pop, n)`` or
    zero-sized for no traces; ``fitness, status (n_pop,)`` written in place.
    ``P, CP`` must be packed for ``n_sub`` (ValueError otherwise).

    Runs the compiled variant of :func:`_kernel_body` for the drive (its options at their
    defaults or not) and the inverter (no candidate losing a volt to dead time, or some):
    each variant is compiled the first time it is needed, so a job compiles only its own.
    """
    key = variant_key(P, CP)
    wait_for(key)                      # a child compiling it (emaphm.models.warm)
    _VARIANTS[key](P, CP, theta_ref, T_load, n_sub, i_target, weights, out_i, out_theta,
                   out_omega, out_torque, fitness, status, out_f)


def _kernel_body(P, CP, theta_ref, T_load, n_sub, i_target, weights,
                 out_i, out_theta, out_omega, out_torque, fitness, status, out_f):
    """:func:`_kernel`'s loop, its stages named by the variant (:data:`_VARIANTS`)."""
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
    ctl = _read_ctl(P, P_CTL)
    I_trip = P[P_I_TRIP]
    n_blk = (n_pop + LANES - 1) // LANES
    B = np.zeros((n_blk, N_ROWS, LANES))
    x0 = initial_x_inline(P[P_THETA0])
    for b in range(n_blk):
        for l in range(LANES):
            # padding lanes repeat the last candidate; their results are not written out
            j = min(b * LANES + l, n_pop - 1)
            for e in range(N_CP):
                B[b, R_C + e, l] = CP[j, e]
            _put_x(B, R_X, b, l, x0)
            _put_x(B, W_X, b, l, x0)
            B[b, R_ALIVE, l] = 1.0
    ta = tb = tc = wa = wb = wc = 0.0
    for k in range(n):
        if with_fit:
            ta, tb, tc = i_target[k, 0], i_target[k, 1], i_target[k, 2]
            wa, wb, wc = weights[k, 0], weights[k, 1], weights[k, 2]
        _trig_stage(B, p)
        ref, w_ff, T_ff = feedforward(theta_ref[k], theta_ref[max(k - 1, 0)],
                                      theta_ref[max(k - 2, 0)], ctl)
        period = (ta, tb, tc, wa, wb, wc, ref, w_ff, T_ff)
        _control_stage(B, ctl, I_trip, period)
        mech = (T_load[k], J_m, C_m, J_l, C_l, K_c, D_c, dt, P[P_INV_I0])
        _plant_stage(B, True, mech)
        for s in range(1, n_sub):
            _trig_stage(B, p)
            _plant_stage(B, False, mech)
        if store:
            for j in range(n_pop):
                b = j // LANES
                l = j - b * LANES
                if B[b, R_ALIVE, l] != 0.0:
                    out_i[j, k, 0] = B[b, R_X + 9, l]
                    out_i[j, k, 1] = B[b, R_X + 10, l]
                    out_i[j, k, 2] = B[b, R_X + 11, l]
                    out_theta[j, k] = B[b, R_X, l]
                    out_omega[j, k] = B[b, R_X + 1, l]
                    out_torque[j, k] = B[b, R_TQ, l]
        _commit_stage(B)
    for j in range(n_pop):
        b = j // LANES
        l = j - b * LANES
        fitness[j] = B[b, R_Q + Q_FIT, l]
        if B[b, R_ALIVE, l] == 0.0:
            status[j] = STATUS_DIVERGED
        elif B[b, R_Q + Q_TRIP, l] != 0.0:
            status[j] = STATUS_TRIPPED


#: The compiled variants of :func:`_kernel_body` by ``(plain drive, ideal inverter)``
#: (:func:`~emaphm.models._monitoring_common.variant_key`), each cached under its own name.
_VARIANTS = variants(
    _kernel_body, kernel_jit,
    drive={True: dict(_control_stage=_control_stage_plain, _commit_stage=_commit_stage_plain),
           False: dict(_control_stage=_control_stage, _commit_stage=_commit_stage)},
    inverter={True: dict(_plant_stage=_plant_stage_ideal), False: dict(_plant_stage=_plant_stage)})
