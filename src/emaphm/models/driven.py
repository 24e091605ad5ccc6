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
friction, backlash, inertias, load; with the candidate's Stribeck speed, the reference
plant's :func:`~emaphm.models.plant_mechanics.plant_step`, whose dry friction falls from
its static to its dynamic level with speed) are driven by the electromagnetic torque of the
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
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_DELTA, C_ECC, C_ECC_PHASE, C_FDJ,
                     C_FSJ, C_GAMMA, C_GAMMA_END, C_MU_A, C_MU_B, C_MU_C, C_OMEGA_S, C_PHI,
                     C_PHI_END, C_T0, C_V_DT, N_CP, P_C_L, P_C_M, P_D_C, P_J_L, P_J_M, P_K_C, P_POLES, P_T_S)
from .inverter import dead_time_drop
from .mechanics import transmission_step
from .plant_mechanics import plant_step
from .pmsm import (COS_2PI_3, SIN_2PI_3, phase_currents, torque_loops, winding_input,
                   winding_step)
from .step import row_reader
from .windings import Q

__all__ = ["OBSERVER_HZ", "MECH_SUBSTEPS", "observer_gains", "mechanical_scale", "flux_linkage",
           "run", "N_RES"]

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


@jit
def flux_linkage(theta, p, c0_a, c0_b, c0_c, ecc, ecc_phase):
    """``(lambda_a, lambda_b, lambda_c)`` [V s]: the magnets' flux linkage of each phase at
    the motor angle ``theta`` [rad], the antiderivative in ``theta`` of Eq. 2's back-EMF
    coefficient ``c_j = c0_j sin(p theta - phi_j) (1 + ecc cos(theta + ecc_phase + psi_j))``
    (``phi = 0, 2 pi/3, -2 pi/3``, ``psi = 0, 2 pi/3, -2 pi/3``), so that the back-EMF
    averaged over a step is the change of ``lambda`` over it. Also returns the sine and
    cosine of ``p theta`` for the coefficients themselves."""
    x = p * theta
    s, c = math.sin(x), math.cos(x)
    # -cos(p theta - phi_j) / p
    ca = -c / p
    cb = -(c * COS_2PI_3 + s * SIN_2PI_3) / p
    cc = -(c * COS_2PI_3 - s * SIN_2PI_3) / p
    la, lb, lc = c0_a * ca, c0_b * cb, c0_c * cc
    if ecc != 0.0:
        # sin(a) cos(b) = (sin(a + b) + sin(a - b)) / 2, a = p theta - phi_j,
        # b = theta + ecc_phase + psi_j: a + b = (p + 1) theta + ecc_phase for every phase
        # (phi_j = psi_j), a - b = (p - 1) theta - ecc_phase - 2 phi_j
        g = (p + 1.0) * theta + ecc_phase
        up = -math.cos(g) / (p + 1.0)
        h = (p - 1.0) * theta - ecc_phase
        if p > 1.0:
            sh, ch = math.sin(h), math.cos(h)
            # -cos(h - 2 phi_j) / (p - 1): phi_a = 0, phi_b = 2 pi/3, phi_c = -2 pi/3
            da = -ch / (p - 1.0)
            db = -(ch * COS_2PI_3 - sh * SIN_2PI_3) / (p - 1.0)   # cos(h - 4 pi/3)
            dc = -(ch * COS_2PI_3 + sh * SIN_2PI_3) / (p - 1.0)   # cos(h + 4 pi/3)
        else:                       # p = 1: a - b does not turn, sin(const) theta
            da = theta * math.sin(-ecc_phase)
            db = theta * math.sin(-ecc_phase - 4.0 * math.pi / 3.0)
            dc = theta * math.sin(-ecc_phase + 4.0 * math.pi / 3.0)
        la += c0_a * 0.5 * ecc * (up + da)
        lb += c0_b * 0.5 * ecc * (up + db)
        lc += c0_c * 0.5 * ecc * (up + dc)
    return la, lb, lc, s, c


@jit
def _coefficients(theta, s, c, c0_a, c0_b, c0_c, ecc, ecc_phase):
    """Eq. 2's back-EMF coefficients [V s/rad] at ``theta`` from the sine and cosine of
    ``p theta``."""
    s_b = s * COS_2PI_3 - c * SIN_2PI_3
    s_c = s * COS_2PI_3 + c * SIN_2PI_3
    if ecc == 0.0:
        return c0_a * s, c0_b * s_b, c0_c * s_c
    g = theta + ecc_phase
    cg, sg = math.cos(g), math.sin(g)
    return (c0_a * s * (1.0 + ecc * cg),
            c0_b * s_b * (1.0 + ecc * (cg * COS_2PI_3 - sg * SIN_2PI_3)),
            c0_c * s_c * (1.0 + ecc * (cg * COS_2PI_3 + sg * SIN_2PI_3)))


@jit
def _period(c, u, theta1, i_meas1, T_l, z, i, tq, lam, mech_state, p, T_s, i_0, mech):
    """One control period of one candidate: the winding driven by the applied voltages
    ``u`` (less the dead time's drop) and the change of the flux linkage to the next
    measured angle ``theta1``, then the mechanics predicted over the period on the torque
    linear between the samples (the next one's from the measured currents ``i_meas1``).
    Returns the new winding state, phase currents, torque, flux linkages and mechanics."""
    c0_a, c0_b, c0_c = c[C_C0_A], c[C_C0_B], c[C_C0_C]
    ecc, ecc_ph = c[C_ECC], c[C_ECC_PHASE]
    mu_a, mu_b, mu_c = c[C_MU_A], c[C_MU_B], c[C_MU_C]
    V_dt, delta = max(c[C_V_DT], 0.0), c[C_DELTA]
    z0, z1, z2, z3, z4 = z
    ia, ib, ic = i
    la, lb, lc = lam
    thm, wm, thl, wl = mech_state
    J_m, C_m, J_l, C_l, K_c, D_c = mech
    na, nb, nc, s, co = flux_linkage(theta1 + delta, p, c0_a, c0_b, c0_c, ecc, ecc_ph)
    u_a = u[0] - dead_time_drop(ia, V_dt, 1.0 / i_0)
    u_b = u[1] - dead_time_drop(ib, V_dt, 1.0 / i_0)
    u_c = u[2] - dead_time_drop(ic, V_dt, 1.0 / i_0)
    w0, w1, w2, w3, w4 = winding_input(u_a, u_b, u_c, (na - la) / T_s, (nb - lb) / T_s,
                                       (nc - lc) / T_s, mu_a, mu_b, mu_c)
    z0, z1, z2, z3, z4 = winding_step(z0, z1, z2, z3, z4, w0, w1, w2, w3, w4,
                                      c[C_PHI:C_PHI_END], c[C_GAMMA:C_GAMMA_END])
    ja, jb, jc = phase_currents(z0, z1)
    ca, cb, cc = _coefficients(theta1 + delta, s, co, c0_a, c0_b, c0_c, ecc, ecc_ph)
    # the torque of the measured phase currents (the fault loops' of the model)
    tq1 = torque_loops(i_meas1[0], i_meas1[1], i_meas1[2], z2, z3, z4, ca, cb, cc,
                       mu_a, mu_b, mu_c)
    h = T_s / MECH_SUBSTEPS
    omega_s = c[C_OMEGA_S]
    stribeck = omega_s > 0.0 and K_c > 0.0
    for ss in range(MECH_SUBSTEPS):
        T_m = tq + ((ss + 0.5) / MECH_SUBSTEPS) * (tq1 - tq)
        if stribeck:            # the dry friction's drop from static to dynamic with speed
            thm, wm, thl, wl = plant_step(thm, wm, thl, wl, T_m, T_l + c[C_T0], J_m, C_m,
                                          c[C_FSJ], c[C_FDJ], omega_s, J_l, C_l, c[C_BACKLASH],
                                          K_c, D_c, h)
        else:
            thm, wm, thl, wl = transmission_step(thm, wm, thl, wl, T_m, T_l + c[C_T0], J_m, C_m,
                                                 c[C_FSJ], c[C_FDJ], J_l, C_l, c[C_BACKLASH],
                                                 K_c, D_c, h)
    return z0, z1, z2, z3, z4, ja, jb, jc, tq1, na, nb, nc, thm, wm, thl, wl


@jit
def _kernel(P, CP, observer, u, theta, omega0, i_meas, T_load, w_e, w_m, i_0,
            sse, residuals, out_i, out_f, out_theta, out_torque, status):
    """Drive ``CP.shape[0]`` candidates through the ``n = theta.shape[0]`` samples of a
    trace, one candidate after another.

    ``P (N_P,)``, ``CP (n_pop, N_CP)`` packed for one sub-step per period; ``observer =
    (l_1, l_2, scale)`` (:func:`observer_gains`, :func:`mechanical_scale`); ``u (n, 3)``
    the phase voltages [V] applied over each period (the last unused); ``theta (n,)``
    the measured motor angle [rad], ``omega0`` the speed at the first sample [rad/s];
    ``i_meas (n, 3)`` the measured currents [A]; ``T_load (n,)`` [N m]; ``w_e (n, 3)`` and
    ``w_m (n,)`` the weights of the two residuals; ``i_0`` [A]
    (:func:`emaphm.models.inverter.dead_time_width`).
    Writes ``sse (n_pop, 2)`` (the weighted sums of the electrical and the mechanical
    residual; inf for a candidate whose currents left the physical range), and, where
    they are not zero-sized, ``residuals (n_pop, n, 4)`` (model less measured: currents
    [A], then the mechanical residual [A]), ``out_i, out_f (n_pop, n, 3)`` (the phase and
    fault-loop currents), ``out_theta, out_torque (n_pop, n)`` (the predicted angle, the
    air-gap torque); ``status (n_pop,)`` 1 for a diverged candidate.
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
    for j in range(n_pop):
        c = _read_c(CP, 0, j)
        c0_a, c0_b, c0_c = c[C_C0_A], c[C_C0_B], c[C_C0_C]
        ecc, ecc_ph = c[C_ECC], c[C_ECC_PHASE]
        delta = c[C_DELTA]
        # the winding from the measured currents (fault loops at rest)
        z0 = Q[0, 0] * i_meas[0, 0] + Q[1, 0] * i_meas[0, 1] + Q[2, 0] * i_meas[0, 2]
        z1 = Q[1, 1] * i_meas[0, 1] + Q[2, 1] * i_meas[0, 2]
        z2 = z3 = z4 = 0.0
        ia, ib, ic = phase_currents(z0, z1)
        # the observer at the first measured angle and speed, the load in contact
        thm = theta[0]
        wm = omega0
        thl = theta[0]
        wl = omega0
        la, lb, lc, s, co = flux_linkage(theta[0] + delta, p, c0_a, c0_b, c0_c, ecc, ecc_ph)
        ca, cb, cc = _coefficients(theta[0] + delta, s, co, c0_a, c0_b, c0_c, ecc, ecc_ph)
        tq = torque_loops(i_meas[0, 0], i_meas[0, 1], i_meas[0, 2], z2, z3, z4, ca, cb, cc,
                          c[C_MU_A], c[C_MU_B], c[C_MU_C])
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
            if keep_r:
                residuals[j, k, 0] = ra
                residuals[j, k, 1] = rb
                residuals[j, k, 2] = rc
                residuals[j, k, 3] = rm
            if keep_t:
                out_i[j, k, 0] = ia
                out_i[j, k, 1] = ib
                out_i[j, k, 2] = ic
                out_f[j, k, 0] = z2
                out_f[j, k, 1] = z3
                out_f[j, k, 2] = z4
                out_theta[j, k] = thm
                out_torque[j, k] = tq
            if k == n - 1:
                break
            # correct the mechanics with the measured angle, then one period of both
            e = theta[k] - thm
            thm += l_1 * e
            wm += l_2 * e
            (z0, z1, z2, z3, z4, ia, ib, ic, tq, la, lb, lc, thm, wm, thl, wl) = _period(
                c, (u[k, 0], u[k, 1], u[k, 2]), theta[k + 1],
                (i_meas[k + 1, 0], i_meas[k + 1, 1], i_meas[k + 1, 2]), T_load[k], (z0, z1, z2, z3, z4),
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


def run(P, CP, observer, u, theta, omega0, i_meas, T_load, w_e, w_m, i_0, *,
        residuals=False, traces=False):
    """:func:`_kernel` with the outputs allocated: ``(sse (n_pop, 2), status, extra)`` where
    ``extra`` holds ``"residuals"`` and/or ``"i_abc", "f_abc", "theta_m", "torque"`` as
    asked."""
    n_pop, n = CP.shape[0], theta.shape[0]
    sse = np.zeros((n_pop, 2))
    status = np.zeros(n_pop, dtype=np.int64)
    r = np.zeros((n_pop, n, N_RES) if residuals else (0, 0, N_RES))
    shape = (n_pop, n) if traces else (0, 0)
    out_i, out_f = np.zeros(shape + (3,)), np.zeros(shape + (3,))
    out_th, out_tq = np.zeros(shape), np.zeros(shape)
    _kernel(P, CP, observer, u, theta, float(omega0), i_meas, T_load, w_e, w_m, float(i_0),
            sse, r, out_i, out_f, out_th, out_tq, status)
    extra = {}
    if residuals:
        extra["residuals"] = r
    if traces:
        extra.update(i_abc=out_i, f_abc=out_f, theta_m=out_th, torque=out_tq)
    return sse, status, extra
