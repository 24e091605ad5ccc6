"""The monitoring model (MM) vectorised with NumPy: time loop in Python, population in arrays.

A test oracle, kept under ``tests/`` (the package runs the one step of
:mod:`emaphm.models.step`); it exists for two reasons:

* it is the **vectorised-NumPy baseline** of ``benchmarks/bench_models.py``,
  the way the MM would be written without a compiler, against which the Numba
  kernel :func:`emaphm.models.monitoring._kernel` is measured;
* it is an **independent check of the kernel's branch logic**: every scalar
  ``if`` of the physics functions (overcurrent trip, speed/current/voltage
  saturation, min-max modulation, Borello stick/slip friction, backlash
  contact, divergence freeze) is rewritten here as a whole-population
  ``np.where`` mask, so a branch taken wrongly on either side shows up as a
  disagreement in ``tests/models/test_monitoring_numpy.py``.

It evaluates the SAME equations in the SAME order of floating-point operations
as ``_kernel`` and the scalar functions it is built from (``control_step``,
``modulate``, ``back_emf_coeffs``, ``transmission_step``; the branch-free
winding functions ``winding_input``, ``winding_step``, ``phase_currents``,
``torque_loops`` of :mod:`emaphm.models.pmsm` are called as they are, their
pure-Python versions on whole-population arrays), so the two agree to
round-off; the only source of difference is NumPy's ``sin`` and ``cos``
against the libm calls Numba emits (an ulp, now and then). The exact winding
step ``Phi, Gamma`` of every candidate comes packed in ``CP``.

It is slow (a few hundred NumPy calls per control period whatever the
population size): use :class:`emaphm.models.monitoring.MonitoringModel` for work.

Shapes: ``P (N_P,)`` and ``CP (n_pop, N_CP)`` from
:func:`emaphm.models.layout.pack_population`; ``theta_ref`` [rad] and
``T_load`` [N m] ``(n,)`` on the control grid ``k*T_s``; ``i_target`` [A]
and ``weights`` [1/A^2] ``(n, 3)``.
"""

from __future__ import annotations

import math

import numpy as np

from emaphm.models.layout import (C_BACKLASH, C_C0_A, C_ECC, C_ECC_PHASE, C_FDJ, C_FSJ, C_GAMMA, C_KP, C_T0,
                     C_MU_A, C_PHI, P_C_L, P_C_M, P_DT, P_I_MAX, P_J_L, P_J_M, P_K_T, P_KD, P_KI,
                     P_KI_I, P_KI_W, P_KP_I, P_KP_W, P_OMEGA_MAX, P_POLES, P_T_MAX, P_T_S,
                     P_V_DC, P_THETA0, P_I_TRIP, P_K_C, P_D_C)
from emaphm.models._monitoring_common import I_DIVERGED, OMEGA_DIVERGED, STATUS_DIVERGED, STATUS_TRIPPED
from emaphm.models.pmsm import (COS_2PI_3, SIN_2PI_3, phase_currents, torque_loops, winding_input,
                   winding_step)

__all__ = ["weighted_sse_numpy", "simulate_population_numpy"]

SQRT3 = math.sqrt(3.0)


# --- vectorised counterparts of the scalar physics functions (same operation order) ---

def _sat(u, limit):
    """``min(max(u, -limit), limit)`` elementwise."""
    return np.minimum(np.maximum(u, -limit), limit)


def _pi_step(error, integral, Kp, Ki, limit, T_s):
    """PI with back-calculation (controller.pi_step): ``(saturated output, new integral)``."""
    u = Kp * error + integral
    y = _sat(u, limit)
    return y, integral + T_s * Ki * (error + (y - u) / Kp)


def _control_step(theta_ref, theta_m, omega_m, i_a, i_b, i_c, sin_e, cos_e,
                  int_e, int_w, int_d, int_q, Kp, P):
    """controller.control_step over the population; ``Kp (n_pop,)``, the rest from ``P``."""
    Ki, Kd, omega_max = P[P_KI], P[P_KD], P[P_OMEGA_MAX]
    Kp_w, Ki_w, T_max, k_T, I_max = P[P_KP_W], P[P_KI_W], P[P_T_MAX], P[P_K_T], P[P_I_MAX]
    Kp_i, Ki_i, V_dc, T_s = P[P_KP_I], P[P_KI_I], P[P_V_DC], P[P_T_S]
    e = theta_ref - theta_m
    w_ref, int_e = _pi_step(e, int_e, Kp, Ki, omega_max, T_s)
    w_ref = _sat(w_ref - Kd * omega_m, omega_max)
    T_ref, int_w = _pi_step(w_ref - omega_m, int_w, Kp_w, Ki_w, T_max, T_s)
    i_q_ref = _sat(T_ref / k_T, I_max)
    # clarke, park
    i_al = (2.0 * i_a - i_b - i_c) / 3.0
    i_be = (i_b - i_c) / SQRT3
    i_d = i_al * cos_e + i_be * sin_e
    i_q = i_al * sin_e - i_be * cos_e
    v_lim = V_dc / math.sqrt(3.0)
    v_d, int_d = _pi_step(-i_d, int_d, Kp_i, Ki_i, v_lim, T_s)
    v_q, int_q = _pi_step(i_q_ref - i_q, int_q, Kp_i, Ki_i, v_lim, T_s)
    v_q = v_q + (k_T / 1.5) * omega_m
    mag = np.sqrt(v_d * v_d + v_q * v_q)
    over = mag > v_lim
    scale = v_lim / np.where(over, mag, 1.0)
    v_d = np.where(over, v_d * scale, v_d)
    v_q = np.where(over, v_q * scale, v_q)
    # inv_park, inv_clarke
    v_al = v_d * cos_e + v_q * sin_e
    v_be = v_d * sin_e - v_q * cos_e
    v_a = v_al
    v_b = -0.5 * v_al + 0.5 * SQRT3 * v_be
    v_c = -0.5 * v_al - 0.5 * SQRT3 * v_be
    return v_a, v_b, v_c, int_e, int_w, int_d, int_q


def _modulate(v_a, v_b, v_c, V_dc):
    """inverter.modulate: min-max injection, duties clipped to [0, 1]."""
    hi = np.maximum(v_a, np.maximum(v_b, v_c))
    lo = np.minimum(v_a, np.minimum(v_b, v_c))
    off = 0.5 * V_dc - 0.5 * (hi + lo)
    return tuple(np.minimum(np.maximum((v + off) / V_dc, 0.0), 1.0) for v in (v_a, v_b, v_c))


def _back_emf_coeffs(theta_m, sin_e, cos_e, c0, ecc, ecc_phase, any_ecc):
    """pmsm.back_emf_coeffs; ``c0 (n_pop, 3)``. Returns ``c_a, c_b, c_c``."""
    s_a = sin_e
    s_b = sin_e * COS_2PI_3 - cos_e * SIN_2PI_3
    s_c = sin_e * COS_2PI_3 + cos_e * SIN_2PI_3
    r_a, r_b, r_c = c0[:, 0] * s_a, c0[:, 1] * s_b, c0[:, 2] * s_c
    if not any_ecc:
        return r_a, r_b, r_c
    g = theta_m + ecc_phase
    cg = np.cos(g)
    sg = np.sin(g)
    m_a = 1.0 + ecc * cg
    m_b = 1.0 + ecc * (cg * COS_2PI_3 - sg * SIN_2PI_3)
    m_c = 1.0 + ecc * (cg * COS_2PI_3 + sg * SIN_2PI_3)
    no = ecc == 0.0           # the kernel's ``if ecc == 0.0`` branch
    return (np.where(no, r_a, r_a * m_a), np.where(no, r_b, r_b * m_b),
            np.where(no, r_c, r_c * m_c))


def _friction_step(omega, T_act, FSJ, FDJ, J, dt):
    """mechanics.friction_step (Borello stick/slip) with masks for its four exits."""
    moving = omega != 0.0
    sgn = np.where(omega > 0.0, 1.0, -1.0)
    w = omega + dt * (T_act - FDJ * sgn) / J
    w = np.where(w * sgn <= 0.0, 0.0, w)                    # stops inside the step
    sgn_t = np.where(T_act > 0.0, 1.0, -1.0)
    breakaway = np.where(np.abs(T_act) <= FSJ, 0.0, dt * (T_act - FSJ * sgn_t) / J)
    return np.where(moving, w, breakaway)


def _contact_torque(gap, gap_rate, backlash, K_c, D_c):
    """mechanics.contact_torque: zero in the dead band, a spring-damper that only pushes."""
    half = 0.5 * backlash
    push = np.maximum(K_c * (gap - half) + D_c * gap_rate, 0.0)
    pull = np.minimum(K_c * (gap + half) + D_c * gap_rate, 0.0)
    return np.where(gap > half, push, np.where(gap < -half, pull, 0.0))


def _transmission_step(theta_m, omega_m, theta_l, omega_l, T_m, T_l,
                       J_m, C_m, FSJ, FDJ, J_l, C_l, backlash, K_c, D_c, dt):
    """mechanics.transmission_step: the compliant contact (``K_c > 0``, shared by the
    population), or free motion / the coupled body where a rigid gap closes."""
    if K_c > 0.0:
        T_c = _contact_torque(theta_m - theta_l, omega_m - omega_l, backlash, K_c, D_c)
        w_m = _friction_step(omega_m, T_m - C_m * omega_m - T_c, FSJ, FDJ, J_m, dt)
        w_l = omega_l + dt * (T_c - C_l * omega_l - T_l) / J_l
        return theta_m + dt * w_m, w_m, theta_l + dt * w_l, w_l
    w_m = _friction_step(omega_m, T_m - C_m * omega_m, FSJ, FDJ, J_m, dt)
    w_l = omega_l + dt * (-T_l - C_l * omega_l) / J_l
    th_m = theta_m + 0.5 * dt * (w_m + omega_m)
    th_l = theta_l + 0.5 * dt * (w_l + omega_l)
    half = 0.5 * backlash
    gap = th_m - th_l
    free = (-half <= gap) & (gap <= half)
    if free.all():
        return th_m, w_m, th_l, w_l
    side = np.where(gap > 0.0, 1.0, -1.0)
    J = J_m + J_l
    w0 = (J_m * omega_m + J_l * omega_l) / J
    w = _friction_step(w0, T_m - T_l - (C_m + C_l) * w0, FSJ, FDJ, J, dt)
    th_c = theta_m + 0.5 * dt * (w + omega_m)
    return (np.where(free, th_m, th_c), np.where(free, w_m, w),
            np.where(free, th_l, th_c - side * half), np.where(free, w_l, w))


# --- the assembly ----------------------------------------------------------------------

def _run(P, CP, theta_ref, T_load, n_sub, i_target, weights, store):
    P = np.asarray(P, dtype=float)
    CP = np.atleast_2d(np.asarray(CP, dtype=float))
    theta_ref = np.asarray(theta_ref, dtype=float)
    T_load = np.asarray(T_load, dtype=float)
    if isinstance(n_sub, bool) or int(n_sub) != n_sub or n_sub < 1:
        raise ValueError(f"n_sub must be an integer >= 1, got {n_sub!r}")
    n_sub = int(n_sub)
    if P[P_DT] != P[P_T_S] / n_sub:
        raise ValueError("CP holds the winding step for another n_sub: pack the population "
                         "with the n_sub the model runs")
    n_pop, n = CP.shape[0], theta_ref.shape[0]
    if T_load.shape != (n,):
        raise ValueError(f"theta_ref and T_load must have the same shape (n,), got "
                         f"{theta_ref.shape} and {T_load.shape}")
    with_fit = i_target is not None
    if with_fit and (i_target.shape != (n, 3) or weights.shape != (n, 3)):
        raise ValueError(f"target currents and weights must have shape ({n}, 3), got "
                         f"{i_target.shape} and {weights.shape}")
    p = P[P_POLES]
    T_s = P[P_T_S]
    dt = T_s / n_sub
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    V_dc = P[P_V_DC]
    Kp = CP[:, C_KP]
    FSJ, FDJ, backlash = CP[:, C_FSJ], CP[:, C_FDJ], CP[:, C_BACKLASH]
    T_0 = CP[:, C_T0]                  # each candidate's load beside the profile's
    c0 = CP[:, C_C0_A:C_C0_A + 3]
    ecc, ecc_phase = CP[:, C_ECC], CP[:, C_ECC_PHASE]
    any_ecc = bool(np.any(ecc != 0.0))
    # the exact winding step of every candidate: per entry a column (n_pop,), row by row
    mu = tuple(CP[:, C_MU_A + j].copy() for j in range(3))
    Phi = tuple(CP[:, C_PHI + e].copy() for e in range(25))
    Gam = tuple(CP[:, C_GAMMA + e].copy() for e in range(25))
    # state: the winding circuit's z = [y_alpha, y_beta, f_a, f_b, f_c], i_abc = Q y
    zeros = np.zeros(n_pop)
    th_m, w_m, th_l, w_l = zeros + P[P_THETA0], zeros.copy(), zeros + P[P_THETA0], zeros.copy()
    tripped = np.zeros(n_pop, dtype=bool)
    i_a, i_b, i_c = zeros.copy(), zeros.copy(), zeros.copy()
    z_all = tuple(zeros.copy() for _ in range(5))
    integ = [zeros.copy() for _ in range(4)]
    fitness = np.zeros(n_pop)
    alive = np.ones(n_pop, dtype=bool)
    if store:
        out_i = np.zeros((n_pop, n, 3))
        out_th, out_w, out_tq = np.zeros((n_pop, n)), np.zeros((n_pop, n)), np.zeros((n_pop, n))
    for k in range(n):
        ref = theta_ref[k]
        T_l = T_load[k]
        # frozen (diverged) candidates keep their last good state and are masked below
        thm, wm, thl, wl, ia, ib, ic, z = th_m, w_m, th_l, w_l, i_a, i_b, i_c, z_all
        if with_fit:
            da = ia - i_target[k, 0]
            db = ib - i_target[k, 1]
            dc = ic - i_target[k, 2]
            inc = weights[k, 0] * da * da + weights[k, 1] * db * db + weights[k, 2] * dc * dc
            fitness = np.where(alive, fitness + inc, fitness)
        s_e = np.sin(p * thm)
        c_e = np.cos(p * thm)
        # overcurrent trip (inverter.overcurrent): active short circuit, controller stopped
        I_trip = P[P_I_TRIP]
        tripped = tripped | (alive & ((np.abs(ia) > I_trip) | (np.abs(ib) > I_trip)
                                      | (np.abs(ic) > I_trip)))
        v_a, v_b, v_c, e0, e1, e2, e3 = _control_step(ref, thm, wm, ia, ib, ic, s_e, c_e,
                                                      *integ, Kp, P)
        e0, e1, e2, e3 = (np.where(tripped, old, new) for new, old in zip((e0, e1, e2, e3), integ))
        d_a, d_b, d_c = (np.where(tripped, 0.0, d) for d in _modulate(v_a, v_b, v_c, V_dc))
        u_a, u_b, u_c = d_a * V_dc, d_b * V_dc, d_c * V_dc
        for s in range(n_sub):
            if s > 0:
                s_e = np.sin(p * thm)
                c_e = np.cos(p * thm)
            ca, cb, cc = _back_emf_coeffs(thm, s_e, c_e, c0, ecc, ecc_phase, any_ecc)
            tq0 = torque_loops.py_func(ia, ib, ic, *z[2:], ca, cb, cc, *mu)
            if s == 0 and store:
                out_i[alive, k, 0] = ia[alive]
                out_i[alive, k, 1] = ib[alive]
                out_i[alive, k, 2] = ic[alive]
                out_th[alive, k] = thm[alive]
                out_w[alive, k] = wm[alive]
                out_tq[alive, k] = tq0[alive]
            # the winding circuit's exact step (branch-free: the scalar functions as they are)
            w = winding_input.py_func(u_a, u_b, u_c, ca * wm, cb * wm, cc * wm, *mu)
            z = winding_step.py_func(*z, *w, Phi, Gam)
            ia, ib, ic = phase_currents.py_func(z[0], z[1])
            T_m = 0.5 * (tq0 + torque_loops.py_func(ia, ib, ic, *z[2:], ca, cb, cc, *mu))
            thm, wm, thl, wl = _transmission_step(thm, wm, thl, wl, T_m, T_l + T_0, J_m, C_m,
                                                  FSJ, FDJ, J_l, C_l, backlash,
                                                  P[P_K_C], P[P_D_C], dt)
        ok = ((np.abs(ia) < I_DIVERGED) & (np.abs(ib) < I_DIVERGED) & (np.abs(ic) < I_DIVERGED)
              & (np.abs(wm) < OMEGA_DIVERGED) & (np.abs(thm) < 1e9))
        newly = alive & ~ok
        if newly.any():
            fitness = np.where(newly, np.inf, fitness)
            alive = alive & ok
        keep = alive
        th_m, w_m = np.where(keep, thm, th_m), np.where(keep, wm, w_m)
        th_l, w_l = np.where(keep, thl, th_l), np.where(keep, wl, w_l)
        i_a, i_b, i_c = np.where(keep, ia, i_a), np.where(keep, ib, i_b), np.where(keep, ic, i_c)
        z_all = tuple(np.where(keep, new, old) for new, old in zip(z, z_all))
        integ = [np.where(keep, new, old) for new, old in zip((e0, e1, e2, e3), integ)]
    status = np.where(alive, np.where(tripped, STATUS_TRIPPED, 0), STATUS_DIVERGED).astype(np.int64)
    if store:
        return {"i_abc": out_i, "theta_m": out_th, "omega_m": out_w, "torque": out_tq,
                "status": status}
    return fitness, status


def weighted_sse_numpy(P, CP, theta_ref, T_load, n_sub, i_target, weights):
    """Fitness (Eq. 4) of every candidate: ``sum_k sum_j weights[k, j] (i_j - i_target[k, j])^2``.

    Parameters
    ----------
    P, CP : ndarray
        Shared ``(N_P,)`` and per-candidate ``(n_pop, N_CP)`` parameters, as
        :func:`emaphm.models.layout.pack_population` returns them for ``n_sub``
        (ValueError for a population packed for another step).
    theta_ref, T_load : ndarray (n,)
        Position command [rad] and load torque [N m] at the control instants.
    n_sub : int
        Sub-steps per control period.
    i_target, weights : ndarray (n, 3)
        Target phase currents [A] and their weights.

    Returns
    -------
    fitness : ndarray (n_pop,)
        ``inf`` for a candidate that diverged.
    status : ndarray (n_pop,) of int64
        0 ok, 1 diverged (:data:`emaphm.models.monitoring.STATUS_DIVERGED`).
    """
    i_target = np.asarray(i_target, dtype=float)
    weights = np.asarray(weights, dtype=float)
    with np.errstate(all="ignore"):   # frozen/diverging candidates may overflow; masked
        return _run(P, CP, theta_ref, T_load, n_sub, i_target, weights, False)


def simulate_population_numpy(P, CP, theta_ref, T_load, n_sub) -> dict[str, np.ndarray]:
    """Traces of every candidate, sampled at the control instants.

    Arguments as :func:`weighted_sse_numpy`. Returns a dict with ``i_abc
    (n_pop, n, 3)`` [A], ``theta_m`` [rad], ``omega_m`` [rad/s], ``torque``
    [N m] ``(n_pop, n)`` and ``status (n_pop,)``; a diverged candidate's traces
    stop where it left the physical range and are zero after, as the kernel's.
    """
    with np.errstate(all="ignore"):
        return _run(P, CP, theta_ref, T_load, n_sub, None, None, True)
