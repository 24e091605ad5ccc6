"""The monitoring model driven by what the drive recorded: no controller is modelled.

Where a trace carries the phase voltages the drive commanded for each control period,
the winding circuit can be driven by them, with the measured angle, instead of by a
model of the drive's firmware (:mod:`emaphm.models.controller`), whose feed-forwards,
filters and limits differ from drive to drive. Two residuals come out of one pass:

**Electrical.** Each candidate's winding circuit (:mod:`emaphm.models.windings`, the
exact step ``z' = Phi z + Gamma w`` of :mod:`emaphm.models.pmsm`) is driven over control
period ``k`` by the applied phase voltages ``u_k`` (less the inverter's dead time and
device drops, ``V_dt sat(i / i_0)`` per phase,
:func:`~emaphm.models.inverter.dead_time_drop`: the data sheet's ``[inverter]`` dead time
and device drop, and the ``"V_dt"`` searched beside k on top) and by the
back-EMF averaged over the period from the measured angle: the change of the magnets'
flux linkage ``(lambda(theta_{k+1}) - lambda(theta_k)) / T_s`` (:func:`flux_linkage`, the
antiderivative of Eq. 2's back-EMF coefficients), exact however the speed varies within
the period, and free of the drive's speed estimate. The encoder's zero may sit off the
magnet's axis by ``delta`` (the candidate's angle offset). Its currents are compared with
the measured ones at the samples: they depend on the winding and the magnets
(resistance, inductance, flux, shorts, eccentricity, sensors), not on the mechanics.

**Mechanical.** The mechanics (:func:`emaphm.models.mechanics.transmission_step`: dry
friction, backlash, inertias, load; the sliding friction falling from its static to its
dynamic level with speed below the candidate's Stribeck speed,
:func:`~emaphm.models.mechanics.stribeck_factor`, as the reference plant's does) are driven by the electromagnetic torque of the
measured phase currents through the candidate's back-EMF coefficients (and its own
fault-loop currents), so that what the winding model misses does not pass for a torque
(the currents' noise through the observer's low-pass is a few mA of q current, below
their own), and, run open loop, would drift from
the measured angle (an error of a few electrical degrees puts the currents an ampere out
of phase). So they run as a predictor corrected by the measured angle (a
Luenberger observer of bandwidth :data:`OBSERVER_HZ`, gains :func:`observer_gains`): the
residual is its innovation, the measured angle less the predicted one, a step ahead.
A torque the model lacks, ``Delta T``, leaves an innovation of ``Delta T / (J omega_o^2)``
in steady state; the residual is reported in amperes of q current,
``innovation J omega_o^2 / k_T`` (:func:`mechanical_scale`), so that it reads as the
current that would explain it and carries the currents' noise floor.

The kernel (:func:`_kernel`) runs a population, one candidate after another, and writes
each candidate's weighted sums of squares, or its raw residuals, or its traces.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import jit
from ._monitoring_common import I_DIVERGED
from .controller import CTL_DELAY, N_CTL, current_loop
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_DELTA, C_ECC, C_ECC_PHASE, C_FDJ,
                     C_FSJ, C_GAMMA, C_GAMMA_END, C_MU_A, C_MU_B, C_MU_C, C_OMEGA_S, C_PHI,
                     C_PHI_END, C_T0, C_V_DT, N_CP, P_CTL, P_C_L, P_C_M, P_D_C, P_J_L, P_J_M, P_K_C, P_POLES, P_T_S)
from .inverter import dead_time_drop
from .mechanics import stribeck_factor, transmission_step
from .pmsm import (COS_2PI_3, SIN_2PI_3, phase_currents, torque_loops, winding_input,
                   winding_step)
from .step import inlined, row_reader, select, vector_reader
from .windings import Q

__all__ = ["OBSERVER_HZ", "MECH_SUBSTEPS", "observer_gains", "flux_coefficients", "rotate",
           "sample_sines", "mechanical_scale", "flux_linkage",
           "N_RES"]

#: Bandwidth [Hz] of the observer the mechanics run as: slow beside the current loop and
#: the backlash's contact, fast beside the test's motion (so a torque error of friction's
#: size stays an innovation of a few milliradians, not a drift).
OBSERVER_HZ = 40.0

#: Steps of the mechanics per control period. Under a drive's violent transients (a torque
#: feed-forward's step to the torque limit) one step per period leaves the symplectic
#: Euler's error in the backlash contact's deflection for the observer to see (measured
#: on the reference plant with the monitoring model's own mechanics, the mechanical
#: residual's share of the noise floor at the true parameters: 41 at one step, 1.2 at two,
#: 0.34 at four, 0.065 at eight); the torque is taken linear between the samples.
MECH_SUBSTEPS = 4

#: Residuals per sample: three phase currents [A] and the mechanical one [A of q current].
N_RES = 4

_read_c = row_reader(N_CP, "read_c")
_read_ctl = vector_reader(N_CTL, "read_ctl_driven")


def observer_gains(T_s: float, hz: float = OBSERVER_HZ) -> tuple[float, float]:
    """``(l_1, l_2)``: the angle [-] and speed [1/s] gains of the predictor-corrector
    ``x <- x + L (theta_meas - theta_pred)`` that place both poles of its error at
    ``a = exp(-2 pi hz T_s)`` (critically damped): ``l_1 = 1 - a^2``, ``l_2 = (1 - a)^2 /
    T_s``."""
    a = math.exp(-2.0 * math.pi * hz * T_s)
    return 1.0 - a * a, (1.0 - a) ** 2 / T_s


def mechanical_scale(J: float, k_T: float, hz: float = OBSERVER_HZ) -> float:
    """[A/rad]: the q current whose torque leaves an innovation of one radian in steady
    state, ``J (2 pi hz)^2 / k_T``."""
    return J * (2.0 * math.pi * hz) ** 2 / k_T


def flux_coefficients(s, c, sg, cg, theta, p, c0_a, c0_b, c0_c, ecc):
    """``(lambda_a, lambda_b, lambda_c, c_a, c_b, c_c)``: the magnets' flux linkage of each
    phase [V s] at the motor angle ``theta`` [rad] and Eq. 2's back-EMF coefficients
    [V s/rad] there, from the sine and cosine of ``p theta`` (``s, c``) and of ``theta +
    ecc_phase`` (``sg, cg``).

    ``lambda_j`` is the antiderivative in ``theta`` of ``c_j = c0_j sin(p theta - phi_j) (1 +
    ecc cos(theta + ecc_phase + psi_j))`` (``phi = psi = 0, 2 pi/3, -2 pi/3``), so that the
    back-EMF averaged over a step is the change of ``lambda`` over it: ``sin(a) cos(b) =
    (sin(a + b) + sin(a - b)) / 2`` with ``a + b = (p + 1) theta + ecc_phase`` for every
    phase and ``a - b = (p - 1) theta - ecc_phase - 2 phi_j`` (for ``p = 1`` the latter does
    not turn: its integral grows as ``theta``). The sines of ``(p +- 1) theta +- ecc_phase``
    come from the two given by the angle sum; no branch (selects), so that the kernels'
    vector lanes run it.
    """
    s1 = s * cg + c * sg                       # sin, cos of (p + 1) theta + ecc_phase
    c1 = c * cg - s * sg
    s2 = s * cg - c * sg                       # of (p - 1) theta - ecc_phase
    c2 = c * cg + s * sg
    la = c0_a * (-c / p)
    lb = c0_b * (-(c * COS_2PI_3 + s * SIN_2PI_3) / p)
    lc = c0_c * (-(c * COS_2PI_3 - s * SIN_2PI_3) / p)
    up = -c1 / (p + 1.0)
    turning = p > 1.0
    q = select(turning, p - 1.0, 1.0)
    da = select(turning, -c2 / q, theta * s2)
    db = select(turning, -(c2 * COS_2PI_3 - s2 * SIN_2PI_3) / q,
                theta * (COS_2PI_3 * s2 + SIN_2PI_3 * c2))
    dc = select(turning, -(c2 * COS_2PI_3 + s2 * SIN_2PI_3) / q,
                theta * (COS_2PI_3 * s2 - SIN_2PI_3 * c2))
    h = 0.5 * ecc
    s_b = s * COS_2PI_3 - c * SIN_2PI_3
    s_c = s * COS_2PI_3 + c * SIN_2PI_3
    return (la + c0_a * h * (up + da), lb + c0_b * h * (up + db), lc + c0_c * h * (up + dc),
            c0_a * s * (1.0 + ecc * cg),
            c0_b * s_b * (1.0 + ecc * (cg * COS_2PI_3 - sg * SIN_2PI_3)),
            c0_c * s_c * (1.0 + ecc * (cg * COS_2PI_3 + sg * SIN_2PI_3)))


_flux_coefficients = inlined(flux_coefficients)


def flux_linkage(theta, p, c0_a, c0_b, c0_c, ecc, ecc_phase):
    """:func:`flux_coefficients` at ``theta`` (libm's sines): the flux linkages and the
    back-EMF coefficients."""
    return flux_coefficients(math.sin(p * theta), math.cos(p * theta), math.sin(theta + ecc_phase),
                             math.cos(theta + ecc_phase), theta, float(p), c0_a, c0_b, c0_c,
                             ecc)


@jit
def rotate(s, c, sin_a, cos_a):
    """The sine and cosine of ``x + a`` from those of ``x`` and ``a``."""
    return s * cos_a + c * sin_a, c * cos_a - s * sin_a


def sample_sines(theta: np.ndarray, p: int) -> np.ndarray:
    """``(n, 4)``: the sine and cosine of ``p theta`` and of ``theta`` at each measured angle
    (libm's), shared by every candidate; each rotates them by its own encoder offset and
    eccentricity phase (:func:`rotate`), exactly the sines of its own angles to round-off."""
    th = np.asarray(theta, dtype=float)
    return np.ascontiguousarray(np.column_stack([np.sin(p * th), np.cos(p * th), np.sin(th),
                                                 np.cos(th)]))


@jit
def _period(c, u, theta1, trig1, rot, i_meas1, T_l, z, i, tq, lam, mech_state, p, T_s, i_0, mech):
    """One control period of one candidate: the winding driven by the applied voltages
    ``u`` (less the dead time's drop) and the change of the flux linkage to the next
    measured angle ``theta1`` (the sines of ``p theta1`` and ``theta1``, ``trig1``, rotated
    by the candidate's ``rot``: those of ``p delta`` and ``delta + ecc_phase``), then the
    mechanics predicted over the period on the torque linear between the samples (the next
    one's from the measured currents ``i_meas1``). Returns the new winding state, phase
    currents, torque, flux linkages and mechanics."""
    c0_a, c0_b, c0_c = c[C_C0_A], c[C_C0_B], c[C_C0_C]
    ecc, ecc_ph = c[C_ECC], c[C_ECC_PHASE]
    mu_a, mu_b, mu_c = c[C_MU_A], c[C_MU_B], c[C_MU_C]
    V_dt, delta = max(c[C_V_DT], 0.0), c[C_DELTA]
    z0, z1, z2, z3, z4 = z
    ia, ib, ic = i
    la, lb, lc = lam
    thm, wm, thl, wl = mech_state
    J_m, C_m, J_l, C_l, K_c, D_c = mech
    s, co = rotate(trig1[0], trig1[1], rot[0], rot[1])
    sg, cg = rotate(trig1[2], trig1[3], rot[2], rot[3])
    na, nb, nc, ca, cb, cc = _flux_coefficients(s, co, sg, cg, theta1 + delta, p, c0_a, c0_b,
                                                c0_c, ecc)
    u_a = u[0] - dead_time_drop(ia, V_dt, 1.0 / i_0)
    u_b = u[1] - dead_time_drop(ib, V_dt, 1.0 / i_0)
    u_c = u[2] - dead_time_drop(ic, V_dt, 1.0 / i_0)
    w0, w1, w2, w3, w4 = winding_input(u_a, u_b, u_c, (na - la) / T_s, (nb - lb) / T_s,
                                       (nc - lc) / T_s, mu_a, mu_b, mu_c)
    z0, z1, z2, z3, z4 = winding_step(z0, z1, z2, z3, z4, w0, w1, w2, w3, w4,
                                      c[C_PHI:C_PHI_END], c[C_GAMMA:C_GAMMA_END])
    ja, jb, jc = phase_currents(z0, z1)
    # the torque of the measured phase currents (the fault loops' of the model)
    tq1 = torque_loops(i_meas1[0], i_meas1[1], i_meas1[2], z2, z3, z4, ca, cb, cc,
                       mu_a, mu_b, mu_c)
    h = T_s / MECH_SUBSTEPS
    omega_s = max(c[C_OMEGA_S], 0.0)
    FSJ, FDJ = c[C_FSJ], c[C_FDJ]
    # the sliding friction's drop from static to dynamic with speed (Stribeck), at the
    # period's start
    F_d = FDJ + (FSJ - FDJ) * stribeck_factor(wm, omega_s)
    for ss in range(MECH_SUBSTEPS):
        T_m = tq + ((ss + 0.5) / MECH_SUBSTEPS) * (tq1 - tq)
        thm, wm, thl, wl = transmission_step(thm, wm, thl, wl, T_m, T_l + c[C_T0], J_m, C_m,
                                             FSJ, F_d, J_l, C_l, c[C_BACKLASH], K_c, D_c, h)
    return z0, z1, z2, z3, z4, ja, jb, jc, tq1, na, nb, nc, thm, wm, thl, wl


@jit
def _start(c, theta0, trig, i_meas, p):
    """A candidate at the first sample: the rotation of its angles (the sines of ``p
    delta`` and ``delta + ecc_phase``: its own angles are the measured ones rotated), its
    winding from the measured currents (fault loops at rest) and those currents, its flux
    linkages and its torque."""
    delta, ecc_ph = c[C_DELTA], c[C_ECC_PHASE]
    rot = (math.sin(p * delta), math.cos(p * delta), math.sin(delta + ecc_ph),
           math.cos(delta + ecc_ph))
    z0 = Q[0, 0] * i_meas[0, 0] + Q[1, 0] * i_meas[0, 1] + Q[2, 0] * i_meas[0, 2]
    z1 = Q[1, 1] * i_meas[0, 1] + Q[2, 1] * i_meas[0, 2]
    s, co = rotate(trig[0, 0], trig[0, 1], rot[0], rot[1])
    sg, cg = rotate(trig[0, 2], trig[0, 3], rot[2], rot[3])
    la, lb, lc, ca, cb, cc = _flux_coefficients(s, co, sg, cg, theta0 + delta, p, c[C_C0_A],
                                                c[C_C0_B], c[C_C0_C], c[C_ECC])
    tq = torque_loops(i_meas[0, 0], i_meas[0, 1], i_meas[0, 2], 0.0, 0.0, 0.0, ca, cb, cc,
                      c[C_MU_A], c[C_MU_B], c[C_MU_C])
    return rot, (z0, z1, 0.0, 0.0, 0.0), phase_currents(z0, z1), (la, lb, lc), tq


@jit
def _loop_voltages(i_d_ref, i_q_ref, ia, ib, ic, omega, s_e, c_e, loop, ctl, delay):
    """The voltages of the period from the drive's current loop
    (:func:`~emaphm.models.controller.current_loop`) on the candidate's currents, and the
    loop's new state ``(int_d, int_q, v_a, v_b, v_c)`` (its integrals, the voltages computed
    now, which a delay applies in the next period)."""
    int_d, int_q, va1, vb1, vc1 = loop
    va, vb, vc, int_d, int_q = current_loop(i_d_ref, i_q_ref, ia, ib, ic, omega, s_e, c_e,
                                            int_d, int_q, ctl)
    u = (va1, vb1, vc1) if delay != 0.0 else (va, vb, vc)
    return u, (int_d, int_q, va, vb, vc)


@jit
def _keep_residuals(residuals, j, k, w_e, w_m, ra, rb, rc, rm):
    residuals[j, k, 0] = math.sqrt(w_e[k, 0]) * ra
    residuals[j, k, 1] = math.sqrt(w_e[k, 1]) * rb
    residuals[j, k, 2] = math.sqrt(w_e[k, 2]) * rc
    residuals[j, k, 3] = math.sqrt(w_m[k]) * rm


@jit
def _keep_traces(out_i, out_f, out_theta, out_torque, j, k, i, f, thm, tq):
    for e in range(3):
        out_i[j, k, e] = i[e]
        out_f[j, k, e] = f[e]
    out_theta[j, k] = thm
    out_torque[j, k] = tq


@jit
def _kernel(P, CP, observer, u, i_ref, omega, theta, trig, omega0, i_meas, T_load, w_e, w_m,
            i_0, sse, residuals, out_i, out_f, out_theta, out_torque, status):
    """Drive ``CP.shape[0]`` candidates through the ``n = theta.shape[0]`` samples of a
    trace, one candidate after another. ``P (N_P,)``, ``CP (n_pop, N_CP)`` packed for one sub-step per period; ``observer =
    (l_1, l_2, scale)`` (:func:`observer_gains`, :func:`mechanical_scale`); ``u (n, 3)``
    the phase voltages [V] applied over each period (the last unused), or, where ``i_ref
    (n, 2)`` has a row per sample, the drive's recorded current references ``(i_d_ref,
    i_q_ref)`` [A] instead: each candidate's voltages are then the drive's current loop
    (:func:`emaphm.models.controller.current_loop`, its settings ``P``'s, its delay) on its
    own currents at the measured angle, with the measured speed ``omega (n,)`` [rad/s] in
    its feed-forwards (``i_ref`` and ``omega`` of no rows: the voltages ``u``); ``theta (n,)``
    the measured motor angle [rad] and ``trig (n, 4)`` its sines (:func:`sample_sines`),
    ``omega0`` the speed at the first sample [rad/s];
    ``i_meas (n, 3)`` the measured currents [A]; ``T_load (n,)`` [N m]; ``w_e (n, 3)`` and
    ``w_m (n,)`` the weights of the two residuals; ``i_0`` [A]
    (:func:`emaphm.models.inverter.dead_time_width`).
    Writes ``sse (n_pop, 2)`` (the weighted sums of the two residuals; inf for a candidate
    that left the physical range, ``status`` 1), and, where not zero-sized, ``residuals
    (n_pop, n, 4)`` (model less measured, currents [A] and mechanics [A], each times the
    square root of its weight), ``out_i, out_f (n_pop, n, 3)`` (phase and fault-loop
    currents), ``out_theta, out_torque (n_pop, n)`` (predicted angle, air-gap torque).
    """
    n_pop = CP.shape[0]
    n = theta.shape[0]
    keep_r = residuals.shape[0] == n_pop and n_pop > 0
    keep_t = out_i.shape[0] == n_pop and n_pop > 0
    p = P[P_POLES]
    T_s = P[P_T_S]
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    K_c, D_c = P[P_K_C], P[P_D_C]
    l_1, l_2, scale = observer[0], observer[1], observer[2]
    closed = i_ref.shape[0] == n and n > 0
    ctl = _read_ctl(P, P_CTL)
    delay = P[P_CTL + CTL_DELAY]
    for j in range(n_pop):
        c = _read_c(CP, 0, j)
        # the drive's current loop at rest (its integrals, the voltages of the period before)
        int_d = int_q = 0.0
        va1 = vb1 = vc1 = 0.0
        rot, (z0, z1, z2, z3, z4), (ia, ib, ic), (la, lb, lc), tq = _start(c, theta[0], trig,
                                                                           i_meas, p)
        # the observer at the first measured angle and speed, the load in contact
        thm = thl = theta[0]
        wm = wl = omega0
        se = 0.0
        sm = 0.0
        ok = True
        for k in range(n):
            ra = ia - i_meas[k, 0]
            rb = ib - i_meas[k, 1]
            rc = ic - i_meas[k, 2]
            rm = scale * (thm - theta[k])
            se += w_e[k, 0] * ra * ra + w_e[k, 1] * rb * rb + w_e[k, 2] * rc * rc
            sm += w_m[k] * rm * rm
            if keep_r:                  # weighted, as the sums
                _keep_residuals(residuals, j, k, w_e, w_m, ra, rb, rc, rm)
            if keep_t:
                _keep_traces(out_i, out_f, out_theta, out_torque, j, k, (ia, ib, ic),
                             (z2, z3, z4), thm, tq)
            if k == n - 1:
                break
            # correct the mechanics with the measured angle, then one period of both
            e = theta[k] - thm
            thm += l_1 * e
            wm += l_2 * e
            if closed:
                u_k, (int_d, int_q, va1, vb1, vc1) = _loop_voltages(
                    i_ref[k, 0], i_ref[k, 1], ia, ib, ic, omega[k], trig[k, 0], trig[k, 1],
                    (int_d, int_q, va1, vb1, vc1), ctl, delay)
            else:
                u_k = (u[k, 0], u[k, 1], u[k, 2])
            (z0, z1, z2, z3, z4, ia, ib, ic, tq, la, lb, lc, thm, wm, thl, wl) = _period(
                c, u_k, theta[k + 1],
                (trig[k + 1, 0], trig[k + 1, 1], trig[k + 1, 2], trig[k + 1, 3]), rot,
                (i_meas[k + 1, 0], i_meas[k + 1, 1], i_meas[k + 1, 2]), T_load[k],
                (z0, z1, z2, z3, z4),
                (ia, ib, ic), tq, (la, lb, lc), (thm, wm, thl, wl), p, T_s, i_0,
                (J_m, C_m, J_l, C_l, K_c, D_c))
            if not (abs(ia) < I_DIVERGED and abs(ib) < I_DIVERGED and abs(ic) < I_DIVERGED
                    and math.isfinite(thm) and abs(wm) < 1e5):
                ok = False
                break
        if ok and math.isfinite(se) and math.isfinite(sm):
            sse[j, 0] = se
            sse[j, 1] = sm
            status[j] = 0
        else:
            sse[j, 0] = np.inf
            sse[j, 1] = np.inf
            status[j] = 1
