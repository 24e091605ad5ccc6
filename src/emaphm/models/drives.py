"""Drive firmwares that are not emaphm's, for the reference plant: a bench of foreign drives.

emaphm's own drive (:mod:`emaphm.models.controller`) is a cascade that ``[controller]``
describes, options included. Real drives run firmware of their own, with structures no
such description has. The reference plant (:func:`emaphm.models.reference.run_reference`,
``drive=``) runs any of these instead of emaphm's, so that tests and benchmarks judge the
diagnosis on drives it does not model:

``"observer-ip"``
    A servo drive of the usual industrial make: position P with velocity feed-forward, an
    I-P speed controller (integral on the speed error, proportional on the speed alone)
    fed by a **speed observer** (a Luenberger observer on the measured angle driven by the
    torque reference, :data:`OBSERVER_HZ`), a dq current PI with cross-coupling
    decoupling and back-EMF feed-forward on the observed speed, and a **computation delay
    of one period with the angle advanced** by ``1.5 omega_e T_s`` for it.
``"deadbeat"``
    A drive with a **predictive (deadbeat) current controller**: each period it asks for
    the voltage that would bring the dq currents half way to their references in one
    period from the motor's data-sheet model (``R i + L (i_ref - i) / (2 T_s) + omega_e L
    i_cross + e``, no integrator), behind a position PI and a speed PI on a speed low-pass
    filtered at 0.5 ms.
``"stationary-pi"``
    An older make: position P, a **2-DOF speed PI** (proportional on ``0.8 omega_ref -
    omega``) on a speed **differenced from the angle over four periods** (not the sensor's
    speed), and a **per-phase current PI in the stationary frame**: each phase's current
    follows its own sinusoidal reference ``i_q,ref sin(theta_e - phi_j)``, with the
    phase lag such a loop has at speed, no dq frame, no decoupling, no back-EMF
    feed-forward.

Each is a function of the samples and its own state array, with its settings from the
actuator's data sheet (:func:`settings`); :func:`step` runs the one a kind names.
"""

from __future__ import annotations

import math

import numpy as np

from ..firmware import FOREIGN_DRIVES
from ..params import ActuatorParams
from ._jit import jit
from .inverter import clarke, inv_clarke, inv_park, park

__all__ = ["FOREIGN_DRIVES", "DRIVE_KINDS", "N_FOREIGN_STATE", "settings", "step", "kind_of",
           "initial"]

#: The kind number the plant's kernel dispatches on (0 is emaphm's own drive).
DRIVE_KINDS = {"emaphm": 0, **{name: j + 1 for j, name in enumerate(FOREIGN_DRIVES)}}
#: Length of a foreign drive's state array.
N_FOREIGN_STATE = 12
#: Length of a foreign drive's settings array.
N_FOREIGN_SETTINGS = 24

#: Bandwidth [Hz] of the observer-ip drive's speed observer.
OBSERVER_HZ = 150.0


def kind_of(name: str | None) -> int:
    """The kind number of a drive's name (None: emaphm's own)."""
    if name is None:
        return 0
    if name not in DRIVE_KINDS:
        raise ValueError(f"unknown drive {name!r}; choose emaphm or one of "
                         + ", ".join(FOREIGN_DRIVES))
    return DRIVE_KINDS[name]


# settings: the same slots for every foreign drive
(S_KP, S_KI, S_KVFF, S_KP_W, S_KI_W, S_T_MAX, S_I_MAX, S_OMEGA_MAX, S_K_T, S_KP_I, S_KI_I,
 S_R, S_L, S_PSI, S_P, S_V_DC, S_T_S, S_J, S_L1, S_L2, S_A_W, S_K_DB) = range(22)


def settings(params: ActuatorParams) -> np.ndarray:
    """The foreign drives' settings for an actuator, from its data sheet: the gains of
    emaphm's tuning where a structure has the same loop, the motor's own R, L and flux for
    the model-based terms."""
    m, inv, ctl, ld = params.motor, params.inverter, params.controller, params.load
    T_s = inv.T_s
    a = math.exp(-2.0 * math.pi * OBSERVER_HZ * T_s)
    s = np.zeros(N_FOREIGN_SETTINGS)
    s[S_KP] = ctl.Kp
    s[S_KI] = 0.05 * ctl.Kp * ctl.Kp           # a position integral well below the P corner
    s[S_KVFF] = 1.0
    s[S_KP_W] = ctl.Kp_w
    s[S_KI_W] = ctl.Ki_w
    s[S_T_MAX] = m.T_max
    s[S_I_MAX] = m.I_max
    s[S_OMEGA_MAX] = ctl.omega_max
    s[S_K_T] = ctl.k_T
    s[S_KP_I] = inv.Kp_i
    s[S_KI_I] = inv.Ki_i
    s[S_R] = sum(m.R) / 3.0
    s[S_L] = sum(m.L) / 3.0
    s[S_PSI] = ctl.k_T / 1.5 / m.p                # flux linkage [V s] per electrical rad
    s[S_P] = m.p
    s[S_V_DC] = inv.V_dc
    s[S_T_S] = T_s
    s[S_J] = m.J_m + ld.J_l
    s[S_L1] = 1.0 - a * a                         # critically damped observer of the angle
    s[S_L2] = (1.0 - a) ** 2 / T_s
    s[S_A_W] = -math.expm1(-T_s / 5e-4)           # the deadbeat drive's 0.5 ms speed filter
    s[S_K_DB] = 0.5
    return s


@jit
def _sat(u, limit):
    return min(max(u, -limit), limit)


@jit
def _voltage_limit(v_d, v_q, V_dc):
    v_lim = V_dc / math.sqrt(3.0)
    mag = math.sqrt(v_d * v_d + v_q * v_q)
    if mag > v_lim:
        return v_d * v_lim / mag, v_q * v_lim / mag
    return v_d, v_q


@jit
def _observer_ip(refs, theta_m, i_a, i_b, i_c, s_e, c_e, st, s):
    """The observer-ip drive (see the module). State: observed angle and speed, the speed
    and current integrals, the torque reference and the voltages of the period before."""
    ref, ref1 = refs[0], refs[1]
    T_s = s[S_T_S]
    # the speed observer: predict with the last torque reference, correct with the angle
    e = theta_m - st[0]
    st[0] += s[S_L1] * e
    st[1] += s[S_L2] * e
    w_hat = st[1]
    # position P + velocity feed-forward
    w_ref = _sat(s[S_KP] * (ref - theta_m) + s[S_KVFF] * (ref - ref1) / T_s, s[S_OMEGA_MAX])
    # I-P speed loop, integrating only while the output is not saturated
    T_ref = st[2] - s[S_KP_W] * w_hat
    T_sat = _sat(T_ref, s[S_T_MAX])
    if T_sat == T_ref:
        st[2] += T_s * s[S_KI_W] * (w_ref - w_hat)
    i_q_ref = _sat(T_sat / s[S_K_T], s[S_I_MAX])
    # dq current PI with decoupling and back-EMF feed-forward on the observed speed
    i_al, i_be = clarke(i_a, i_b, i_c)
    i_d, i_q = park(i_al, i_be, s_e, c_e)
    w_e = s[S_P] * w_hat
    v_d = s[S_KP_I] * (-i_d) + st[3] - w_e * s[S_L] * i_q
    v_q = s[S_KP_I] * (i_q_ref - i_q) + st[4] + w_e * (s[S_L] * i_d + s[S_PSI])
    v_d, v_q = _voltage_limit(v_d, v_q, s[S_V_DC])
    st[3] += T_s * s[S_KI_I] * (-i_d)
    st[4] += T_s * s[S_KI_I] * (i_q_ref - i_q)
    # applied next period, at the angle it will have then (1.5 periods ahead on average)
    adv = 1.5 * w_e * T_s
    ca, sa = math.cos(adv), math.sin(adv)
    s_n, c_n = s_e * ca + c_e * sa, c_e * ca - s_e * sa
    v_al, v_be = inv_park(v_d, v_q, s_n, c_n)
    v_a, v_b, v_c = inv_clarke(v_al, v_be)
    out_a, out_b, out_c = st[5], st[6], st[7]
    st[5], st[6], st[7] = v_a, v_b, v_c
    # the observer's prediction to the next sample
    st[0] += T_s * st[1]
    st[1] += T_s * T_sat / s[S_J]
    return out_a, out_b, out_c, w_ref, T_sat, i_q_ref


@jit
def _deadbeat(refs, theta_m, omega_m, i_a, i_b, i_c, s_e, c_e, st, s):
    """The deadbeat drive (see the module). State: the position and speed integrals, the
    filtered speed."""
    ref = refs[0]
    T_s = s[S_T_S]
    st[2] += s[S_A_W] * (omega_m - st[2])
    w_f = st[2]
    e = ref - theta_m
    w_pi = s[S_KP] * e + st[0]
    w_ref = _sat(w_pi, s[S_OMEGA_MAX])
    if w_ref == w_pi:
        st[0] += T_s * s[S_KI] * e
    T_pi = s[S_KP_W] * (w_ref - w_f) + st[1]
    T_ref = _sat(T_pi, s[S_T_MAX])
    if T_ref == T_pi:
        st[1] += T_s * s[S_KI_W] * (w_ref - w_f)
    i_q_ref = _sat(T_ref / s[S_K_T], s[S_I_MAX])
    i_al, i_be = clarke(i_a, i_b, i_c)
    i_d, i_q = park(i_al, i_be, s_e, c_e)
    w_e = s[S_P] * omega_m
    g = s[S_K_DB] * s[S_L] / T_s
    v_d = s[S_R] * i_d + g * (0.0 - i_d) - w_e * s[S_L] * i_q
    v_q = s[S_R] * i_q + g * (i_q_ref - i_q) + w_e * (s[S_L] * i_d + s[S_PSI])
    v_d, v_q = _voltage_limit(v_d, v_q, s[S_V_DC])
    v_al, v_be = inv_park(v_d, v_q, s_e, c_e)
    v_a, v_b, v_c = inv_clarke(v_al, v_be)
    return v_a, v_b, v_c, w_ref, T_ref, i_q_ref


@jit
def _stationary_pi(refs, theta_m, i_a, i_b, i_c, s_e, c_e, st, s):
    """The stationary-pi drive (see the module). State: the speed integral, each phase's
    current integral, the last four angles (oldest first)."""
    ref = refs[0]
    T_s = s[S_T_S]
    w_hat = (theta_m - st[4]) / (4.0 * T_s)               # over four periods
    st[4], st[5], st[6], st[7] = st[5], st[6], st[7], theta_m
    w_ref = _sat(s[S_KP] * (ref - theta_m), s[S_OMEGA_MAX])
    T_pi = s[S_KP_W] * (0.8 * w_ref - w_hat) + st[0]
    T_ref = _sat(T_pi, s[S_T_MAX])
    if T_ref == T_pi:
        st[0] += T_s * s[S_KI_W] * (w_ref - w_hat)
    i_q_ref = _sat(T_ref / s[S_K_T], s[S_I_MAX])
    # each phase on its own: i_j,ref = i_q,ref sin(theta_e - phi_j), a PI per phase
    s_b = s_e * -0.5 - c_e * (0.5 * math.sqrt(3.0))
    s_c = s_e * -0.5 + c_e * (0.5 * math.sqrt(3.0))
    r_a, r_b, r_c = i_q_ref * s_e, i_q_ref * s_b, i_q_ref * s_c
    kp, ki = 2.0 * s[S_KP_I], 2.0 * s[S_KI_I]     # a stationary loop needs the gain
    v_a = kp * (r_a - i_a) + st[1]
    v_b = kp * (r_b - i_b) + st[2]
    v_c = kp * (r_c - i_c) + st[3]
    st[1] += T_s * ki * (r_a - i_a)
    st[2] += T_s * ki * (r_b - i_b)
    st[3] += T_s * ki * (r_c - i_c)
    lim = s[S_V_DC] / math.sqrt(3.0)
    return _sat(v_a, lim), _sat(v_b, lim), _sat(v_c, lim), w_ref, T_ref, i_q_ref


@jit
def initial(kind, theta0, st):
    """A foreign drive's state at rest at the angle ``theta0`` (in place): the observer's
    angle (observer-ip), the last four angles (stationary-pi)."""
    if kind == 1:
        st[0] = theta0
    elif kind == 3:
        for j in range(4, 8):
            st[j] = theta0


@jit
def step(kind, refs, theta_m, omega_m, i_a, i_b, i_c, s_e, c_e, st, s):
    """One control period of the foreign drive ``kind`` (:data:`DRIVE_KINDS`) from the
    samples, its state array ``st`` (updated in place) and settings ``s``
    (:func:`settings`). Returns ``(v_a, v_b, v_c, omega_ref, T_ref, i_q_ref)``: the phase
    voltages it applies this period [V] and its references."""
    if kind == 1:
        return _observer_ip(refs, theta_m, i_a, i_b, i_c, s_e, c_e, st, s)
    if kind == 3:
        return _stationary_pi(refs, theta_m, i_a, i_b, i_c, s_e, c_e, st, s)
    return _deadbeat(refs, theta_m, omega_m, i_a, i_b, i_c, s_e, c_e, st, s)
