"""Reference model (RM): the high-fidelity "numerical test bench", a *plant* that
is not a twin of the monitoring model.

The same drive firmware as the monitoring model (cascade controller and dq
current loop, :func:`emaphm.models.controller.control_step`, sampled once per
PWM period ``T_s``), but the inverter **switches**: each leg is on while a
symmetric triangular carrier is below its duty cycle. Every control period is
cut into ``n_sub`` (even, default 128, about 1 us at 8 kHz) sub-steps; each
sub-step applies the exact volt-seconds of the switched leg voltage
(:func:`emaphm.models.inverter.on_fraction`), so the current ripple is
resolved and no duty is lost to the step. Currents are sampled at the carrier
valley, where a real drive samples them (the ripple's mean).

Electrics (:mod:`emaphm.models.windings`)
-----------------------------------------
The winding circuit with self and mutual inductance and a leakage share
``Motor.L_sigma``, and one fault loop per phase with a shorted fraction
``mu_j > 0`` (phases without a short have no loop state). In the reduced
state ``z = [y, f]`` (zero-sum phase currents ``i = Q y``, fault-loop currents
``f``; ``x = S z = [i, f]``)::

    L_r dz/dt = -R_r z + S^T (v - T^T c omega_m)
    T_m = c . (T x) = sum_j c_j (i_j - mu_j f_j)

integrated by the trapezoidal rule (Crank-Nicolson) over each sub-step ``h``
with the leg voltages ``v`` and the back-EMF ``c omega_m`` (coefficients and
speed at the sub-step start) held::

    (L_r + h/2 R_r) z' = (L_r - h/2 R_r) z + h S^T (v - T^T c omega_m)

The system is linear and time-invariant (surface PMSM, no saliency), so the
step matrices are computed once per run (:func:`electrical_step`). The star
point drops out of the zero-sum basis. Under ``fault_model="paper"`` the
phases are the paper's three uncoupled RL branches (Eq. 5, leakage share 1,
as :mod:`emaphm.models.windings` states), so the paper's scenarios keep their
meaning; under ``"physical"`` the motor's own ``L_sigma`` couples them.

Mechanics (:mod:`emaphm.models.plant_mechanics`)
------------------------------------------------
Motor and load are two bodies joined by a backlash dead band closed by a
compliant, damped contact (``Transmission.K_c``, ``Transmission.D_c``); the motor side has
dry friction with a Stribeck drop (``Transmission.omega_s`` where the file states it,
else ``Plant.omega_s``), Borello's stick/slip at
rest. The mechanics see the sub-step's mean air-gap torque.

Energy bookkeeping
------------------
With the trapezoidal definitions (``x_m`` the mean of the sub-step's start and
end states) the Crank-Nicolson step satisfies exactly, per sub-step::

    h v . i_m = h x_m^T R_x x_m + h T_m(x_m) omega_m + [1/2 x^T L_x x]

(input = copper and fault-loop loss + air-gap work + change of stored magnetic
energy), so the recorded energies balance to round-off.

The traces are the true signals; the acquisition chain of the PHM recorder
(noise, quantisation, sensor gains) lives in :mod:`emaphm.acquisition`. The
drive's own loop sees the clean signals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..faults import apply_faults, as_k, check_fault_model
from ..params import ActuatorParams, Motor
from ..profiles import Profile
from ._jit import jit
from .controller import N_CTL, N_STATE, control_step, feedforward
from .drives import N_FOREIGN_STATE, kind_of, settings as foreign_settings, step as foreign_step
from .drives import initial as foreign_initial
from .inverter import modulate, on_fraction, overcurrent, triangle
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_ECC, C_ECC_PHASE, C_FDJ, C_FSJ, C_KP,
                     C_R_A, P_C_L, P_C_M, P_CTL, P_J_L, P_J_M, P_POLES, P_I_TRIP, P_T_S,
                     P_K_C, P_D_C, P_THETA0, P_V_DC, pack)
from .mechanics import transmission_step
from .plant_mechanics import plant_step
from .pmsm import back_emf_coeffs
from .step import vector_reader
from .windings import Q, winding_matrices

__all__ = ["ElectricalStep", "electrical_step", "run_reference"]

_read_ctl = vector_reader(N_CTL, "read_ctl")
_read_state = vector_reader(N_STATE, "read_state")

# i = Q y with Q's structure: i_a = Q_A y0, i_b = Q_B y0 + Q_C y1, i_c = Q_B y0 - Q_C y1
Q_A = float(Q[0, 0])
Q_B = float(Q[1, 0])
Q_C = float(Q[1, 1])


@dataclass(frozen=True)
class ElectricalStep:
    """The Crank-Nicolson step of the winding circuit over a sub-step ``h`` [s].

    ``z' = A z + B_v v - G e`` for leg voltages ``v`` [V] and back-EMFs
    ``e = c omega_m`` [V] held over the step, ``z = [y, f]`` with ``n_z = 2 +
    len(loops)`` states: the zero-sum phase currents ``y`` (``i = Q y``) and
    the fault-loop currents of the phases in ``loops``. ``S`` ``(6, n_z)`` maps
    ``z`` to ``x = [i_a, i_b, i_c, f_a, f_b, f_c]``; ``L_x, R_x`` ``(6, 6)`` the
    winding matrices, ``L_r = S^T L_x S`` and ``R_r = S^T R_x S``.
    """

    h: float
    A: np.ndarray
    B_v: np.ndarray
    G: np.ndarray
    S: np.ndarray
    L_x: np.ndarray
    R_x: np.ndarray
    L_r: np.ndarray
    R_r: np.ndarray
    loops: np.ndarray
    mu: np.ndarray
    R_f: np.ndarray


def electrical_step(motor: Motor, h: float, fault_model: str = "paper") -> ElectricalStep:
    """Step matrices of :class:`ElectricalStep` for ``motor`` (faults applied) and
    sub-step ``h`` [s].

    ``fault_model="paper"`` uses the paper's uncoupled phases (leakage share 1),
    ``"physical"`` the motor's ``L_sigma``.
    """
    check_fault_model(fault_model)
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"electrical sub-step h [s] must be > 0, got {h!r}")
    sigma = 1.0 if fault_model == "paper" else motor.L_sigma
    mu = np.array(motor.mu, dtype=float)
    R_f = np.array(motor.R_f, dtype=float)
    L_x, R_x = winding_matrices(motor.R, motor.L, sigma, mu, R_f)
    loops = np.flatnonzero(mu > 0.0).astype(np.int64)
    S = np.zeros((6, 2 + loops.size))
    S[:3, :2] = Q
    S[3 + loops, 2 + np.arange(loops.size)] = 1.0
    L_r = S.T @ L_x @ S
    R_r = S.T @ R_x @ S
    M = L_r + 0.5 * h * R_r
    A = np.linalg.solve(M, L_r - 0.5 * h * R_r)
    B = h * np.linalg.solve(M, S.T)                       # (n_z, 6): the input u = v - T^T e
    T_t = np.vstack([np.eye(3), -np.diag(mu)])            # T^T (6, 3)
    return ElectricalStep(h=float(h), A=A, B_v=np.ascontiguousarray(B[:, :3]),
                          G=np.ascontiguousarray(B @ T_t), S=S, L_x=L_x, R_x=R_x, L_r=L_r,
                          R_r=R_r, loops=loops, mu=mu, R_f=R_f)


@jit
def _sign(x):
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)


@jit
def _rm_kernel(P, cp, plant, A, B_v, G, L_r, loops, mu, R_f, theta_ref, T_load, n_sub, pwm,
               mm_mechanics, out_i, out_f, out_ripple, out_theta, out_omega, out_torque, out_energy,
               out_drive, trip_index, kind, foreign):
    """One actuator over ``theta_ref.shape[0]`` control periods at step ``T_s/n_sub``.

    ``plant = [omega_s, K_c, D_c, V_lost]`` (``V_lost`` [V]: what a leg loses to dead
    time and device drops, against the sign of its current at the sub-step's start);
    ``A, B_v, G, L_r`` from :func:`electrical_step`
    at that step, ``loops`` the phases with a fault loop, ``mu, R_f`` per phase.
    ``kind``: the drive's firmware (:data:`emaphm.models.drives.DRIVE_KINDS`; 0 emaphm's
    own, run on ``P``'s settings; else a foreign drive on its settings ``foreign``).
    ``mm_mechanics`` swaps the plant mechanics for the monitoring model's
    (:func:`emaphm.models.mechanics.transmission_step` with ``P``'s contact; for
    comparisons only).
    ``out_ripple (n, 3)`` receives the RMS of each fault-loop current about its mean
    over the sub-step ends of control period ``k`` (the PWM ripple the samples miss).
    ``out_energy (n, 4)`` receives cumulative [input, copper and fault-loop
    loss, air-gap (T_m * omega_m), stored magnetic] energies in J at each
    sample; ``out_drive (n, 6)`` what the drive logs each period: the phase voltage
    references it applies [V] (star-referenced), ``i_d_ref`` (0), ``i_q_ref`` [A] and
    ``omega_ref`` [rad/s] (zero once tripped); ``trip_index[0]`` the sample at which the
    drive tripped on overcurrent (-1: never).
    """
    n = theta_ref.shape[0]
    nz = A.shape[0]
    nl = nz - 2
    p = P[P_POLES]
    T_s = P[P_T_S]
    dt = T_s / n_sub
    V_dc = P[P_V_DC]
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    omega_s, K_c, D_c, V_lost = plant[0], plant[1], plant[2], plant[3]
    R_a, R_b, R_c = cp[C_R_A], cp[C_R_A + 1], cp[C_R_A + 2]
    mu_a, mu_b, mu_c = mu[0], mu[1], mu[2]
    thm = P[P_THETA0]
    wm = 0.0
    thl = P[P_THETA0]
    wl = 0.0
    z = np.zeros(nz)
    zn = np.zeros(nz)
    f = np.zeros(3)                    # fault-loop currents by phase
    fm = np.zeros(3)
    f_sum = np.zeros(3)
    f_sq = np.zeros(3)
    ia = 0.0
    ib = 0.0
    ic = 0.0
    ctl = _read_ctl(P, P_CTL)
    cs = _read_state(np.zeros(N_STATE), 0)         # the drive's state, at rest
    fst = np.zeros(N_FOREIGN_STATE)                # a foreign drive's, at rest
    foreign_initial(kind, thm, fst)
    E_in = 0.0
    E_loss = 0.0
    E_ag = 0.0
    tripped = False
    trip_index[0] = -1
    for k in range(n):
        s_e = math.sin(p * thm)
        c_e = math.cos(p * thm)
        ca, cb, cc = back_emf_coeffs(thm, s_e, c_e, cp[C_C0_A], cp[C_C0_B], cp[C_C0_C],
                                     cp[C_ECC], cp[C_ECC_PHASE])
        out_i[k, 0] = ia
        out_i[k, 1] = ib
        out_i[k, 2] = ic
        out_f[k, 0] = f[0]
        out_f[k, 1] = f[1]
        out_f[k, 2] = f[2]
        out_theta[k] = thm
        out_omega[k] = wm
        out_torque[k] = ca * (ia - mu_a * f[0]) + cb * (ib - mu_b * f[1]) + cc * (ic - mu_c * f[2])
        out_energy[k, 0] = E_in
        out_energy[k, 1] = E_loss
        out_energy[k, 2] = E_ag
        E_mag = 0.0
        for r in range(nz):
            acc = 0.0
            for q in range(nz):
                acc += L_r[r, q] * z[q]
            E_mag += z[r] * acc
        out_energy[k, 3] = 0.5 * E_mag
        if not tripped and overcurrent(ia, ib, ic, P[P_I_TRIP]):
            tripped = True
            trip_index[0] = k
        if tripped:                    # active short circuit, controller stopped
            d_a = d_b = d_c = 0.0
            for j in range(6):
                out_drive[k, j] = 0.0
        else:
            if kind == 0:
                v_a, v_b, v_c, refs, cs = control_step(
                    feedforward(theta_ref[k], theta_ref[max(k - 1, 0)], theta_ref[max(k - 2, 0)],
                                ctl), thm, wm, ia, ib, ic, s_e, c_e, cs, cp[C_KP], ctl)
                w_ref, i_q_ref = refs[0], refs[2]
            else:
                v_a, v_b, v_c, w_ref, _, i_q_ref = foreign_step(
                    kind, (theta_ref[k], theta_ref[max(k - 1, 0)]), thm, wm, ia, ib, ic, s_e, c_e,
                    fst, foreign)
            d_a, d_b, d_c = modulate(v_a, v_b, v_c, V_dc)
            out_drive[k, 0] = v_a
            out_drive[k, 1] = v_b
            out_drive[k, 2] = v_c
            out_drive[k, 3] = 0.0
            out_drive[k, 4] = i_q_ref
            out_drive[k, 5] = w_ref
        for j in range(3):
            f_sum[j] = 0.0
            f_sq[j] = 0.0
        for s in range(n_sub):
            if s > 0:
                s_e = math.sin(p * thm)
                c_e = math.cos(p * thm)
                ca, cb, cc = back_emf_coeffs(thm, s_e, c_e, cp[C_C0_A], cp[C_C0_B], cp[C_C0_C],
                                             cp[C_ECC], cp[C_ECC_PHASE])
            if pwm:
                c0 = triangle(s / n_sub)
                c1 = triangle((s + 1) / n_sub)
                va = V_dc * on_fraction(d_a, c0, c1)
                vb = V_dc * on_fraction(d_b, c0, c1)
                vc = V_dc * on_fraction(d_c, c0, c1)
            else:
                va = V_dc * d_a
                vb = V_dc * d_b
                vc = V_dc * d_c
            if V_lost > 0.0 and not tripped:    # dead time and device drops, against i
                va -= V_lost * _sign(ia)
                vb -= V_lost * _sign(ib)
                vc -= V_lost * _sign(ic)
            ea = ca * wm
            eb = cb * wm
            ec = cc * wm
            # Crank-Nicolson: z' = A z + B_v v - G e
            for r in range(nz):
                acc = B_v[r, 0] * va + B_v[r, 1] * vb + B_v[r, 2] * vc \
                    - G[r, 0] * ea - G[r, 1] * eb - G[r, 2] * ec
                for q in range(nz):
                    acc += A[r, q] * z[q]
                zn[r] = acc
            y0 = 0.5 * (z[0] + zn[0])              # sub-step means (trapezoid)
            y1 = 0.5 * (z[1] + zn[1])
            ima = Q_A * y0
            imb = Q_B * y0 + Q_C * y1
            imc = Q_B * y0 - Q_C * y1
            for j in range(nl):
                fm[loops[j]] = 0.5 * (z[2 + j] + zn[2 + j])
            # healthy turns carry i, shorted turns i - f, the fault resistance f:
            # x_m^T R_x x_m per phase = R i^2 - 2 mu R i f + (mu R + R_f) f^2
            p_loss = (R_a * ima * ima + R_b * imb * imb + R_c * imc * imc
                      + fm[0] * ((mu_a * R_a + R_f[0]) * fm[0] - 2.0 * mu_a * R_a * ima)
                      + fm[1] * ((mu_b * R_b + R_f[1]) * fm[1] - 2.0 * mu_b * R_b * imb)
                      + fm[2] * ((mu_c * R_c + R_f[2]) * fm[2] - 2.0 * mu_c * R_c * imc))
            T_mean = (ca * (ima - mu_a * fm[0]) + cb * (imb - mu_b * fm[1])
                      + cc * (imc - mu_c * fm[2]))
            E_in += dt * (va * ima + vb * imb + vc * imc)
            E_loss += dt * p_loss
            E_ag += dt * T_mean * wm
            for r in range(nz):
                z[r] = zn[r]
            ia = Q_A * z[0]
            ib = Q_B * z[0] + Q_C * z[1]
            ic = Q_B * z[0] - Q_C * z[1]
            for j in range(nl):
                fj = z[2 + j]
                f[loops[j]] = fj
                f_sum[j] += fj
                f_sq[j] += fj * fj
            if mm_mechanics:
                thm, wm, thl, wl = transmission_step(thm, wm, thl, wl, T_mean, T_load[k], J_m, C_m,
                                                     cp[C_FSJ], cp[C_FDJ], J_l, C_l,
                                                     cp[C_BACKLASH], P[P_K_C], P[P_D_C], dt)
            else:
                thm, wm, thl, wl = plant_step(thm, wm, thl, wl, T_mean, T_load[k], J_m, C_m,
                                              cp[C_FSJ], cp[C_FDJ], omega_s, J_l, C_l,
                                              cp[C_BACKLASH], K_c, D_c, dt)
        for j in range(nl):
            mean = f_sum[j] / n_sub
            out_ripple[k, loops[j]] = math.sqrt(max(f_sq[j] / n_sub - mean * mean, 0.0))


def _run(params: ActuatorParams, k, profile: Profile, *, fault_model: str, n_sub: int, pwm: bool,
         extra_load: float, mm_mechanics: bool, drive: str | None = None) -> dict:
    if isinstance(n_sub, bool) or not isinstance(n_sub, int) or n_sub < 2 or n_sub % 2:
        raise ValueError(f"reference model n_sub must be an even integer >= 2 (sub-steps per "
                         f"PWM period, so that none straddles the carrier peak), got {n_sub!r}")
    if isinstance(extra_load, bool) or not isinstance(extra_load, (int, float, np.floating)) \
            or not math.isfinite(extra_load):
        raise ValueError(f"extra_load [N m] must be a finite number, got {extra_load!r}")
    kind = kind_of(drive)
    # a foreign drive's settings are the healthy actuator's data sheet, as its commissioning
    foreign = foreign_settings(params)
    faulty = apply_faults(params, as_k(k), fault_model)
    P, CP = pack(faulty, fault_model=fault_model, n_sub=n_sub)
    T_s = params.inverter.T_s
    el = electrical_step(faulty.motor, T_s / n_sub, fault_model)
    pl = faulty.plant
    tr = faulty.transmission
    # the Stribeck speed the unit's file states (or its calibration estimated), else the
    # plant's own
    omega_s = tr.omega_s if tr.omega_s > 0.0 else pl.omega_s
    plant = np.array([omega_s, tr.K_c, tr.D_c, faulty.inverter.V_lost])
    t = profile.grid(T_s)
    ref = np.ascontiguousarray(profile.theta_ref(t))
    load = np.ascontiguousarray(profile.load_torque(t) + float(extra_load))
    n = t.size
    out = {"i_abc": np.zeros((n, 3)), "i_fault": np.zeros((n, 3)),
           "i_fault_ripple": np.zeros((n, 3)), "theta_m": np.zeros(n),
           "omega_m": np.zeros(n), "torque": np.zeros(n), "energy": np.zeros((n, 4)),
           "drive": np.zeros((n, 6))}
    trip = np.full(1, -1, dtype=np.int64)
    _rm_kernel(P, CP[0], plant, el.A, el.B_v, el.G, el.L_r, el.loops, el.mu, el.R_f, ref, load,
               n_sub, bool(pwm), bool(mm_mechanics), out["i_abc"], out["i_fault"], out["i_fault_ripple"],
               out["theta_m"], out["omega_m"], out["torque"], out["energy"], out["drive"], trip,
               kind, foreign)
    out.update(t=t, theta_ref=ref, trip_time=None if trip[0] < 0 else float(t[trip[0]]))
    return out


def run_reference(params: ActuatorParams, k, profile: Profile, *, fault_model: str = "paper",
                  n_sub: int = 128, pwm: bool = True, extra_load: float = 0.0,
                  drive: str | None = None) -> dict[str, np.ndarray]:
    """Simulate the faulty plant ``apply_faults(params, k, fault_model)`` with ideal sensors.

    ``n_sub`` even sub-steps per control period; ``pwm`` switching (True) or
    averaged (False) inverter; ``extra_load`` [N m] a constant load torque added
    to the profile's (a load the bench does not report).

    Returns a dict ``t, theta_ref, theta_m, omega_m, i_abc (n, 3), i_fault (n, 3)``
    (fault-loop currents, zero on a phase without a short), ``i_fault_ripple (n, 3)``
    (RMS of each fault-loop current about its mean within the control period
    that starts at the sample: the PWM ripple the samples miss), ``torque`` (air-gap,
    fault loops included), ``energy (n, 4)`` (cumulative input, copper and
    fault-loop loss, air-gap work, and the stored magnetic energy, J) sampled at
    the control instants ``k*T_s``, ``drive (n, 6)`` (what the drive logs each period:
    the phase voltage references it applies, star-referenced [V], ``i_d_ref`` [A, 0],
    ``i_q_ref`` [A] and ``omega_ref`` [rad/s]), and ``trip_time`` [s] when the drive
    tripped on overcurrent (None if never). ``params.inverter.dead_time`` and
    ``device_drop`` take their voltage off each leg against its current's sign.
    ``drive``: the firmware the plant's drive runs, emaphm's own (None, ``"emaphm"``: the
    cascade ``params.controller`` describes) or a foreign one of
    :data:`emaphm.models.drives.FOREIGN_DRIVES`, set up from ``params``' data sheet.
    """
    return _run(params, k, profile, fault_model=fault_model, n_sub=n_sub, pwm=pwm,
                extra_load=extra_load, mm_mechanics=False, drive=drive)
