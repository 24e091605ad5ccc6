"""Discrete cascade controller of the drive, run once per control period T_s.

position PID -> speed reference (saturated at omega_max)
speed PI     -> torque reference (saturated at T_max)
i_q,ref = T_ref / k_T (saturated at I_max), i_d,ref = 0
dq current PI with back-EMF feed-forward -> phase voltage references
(the textbook dq frame, d on the magnet's flux: :mod:`emaphm.models.inverter`)

Every integrator has back-calculation anti-windup (Astrom & Hagglund): while
the output saturates, the integral is pulled towards the saturated value with
the tracking time constant ``T_t = Kp/Ki`` (the integral time). Unlike a
clamp that switches integration on and off, this is continuous in the gains,
so the fitness landscape has no step where a transient just touches a limit.
The controller
knows the healthy motor only (``k_T``, its ``c0 = k_T/1.5``); faults change
the plant, never the controller's model of it, except k8, which drifts ``Kp``.
"""

import math

from ._jit import jit
from .inverter import clarke, inv_clarke, inv_park, park


@jit
def _sat(u, limit):
    return min(max(u, -limit), limit)


@jit
def pi_step(error, integral, Kp, Ki, limit, T_s):
    """One PI update with back-calculation: returns (saturated output, new integral).

    The integral is in output units (it already carries Ki);
    ``d(integral)/dt = Ki*error + (Ki/Kp)*(y - u)``.
    """
    u = Kp * error + integral
    y = _sat(u, limit)
    return y, integral + T_s * Ki * (error + (y - u) / Kp)


@jit
def control_step(theta_ref, theta_m, omega_m, i_a, i_b, i_c, sin_e, cos_e,
                 int_e, int_w, int_d, int_q,
                 Kp, Ki, Kd, omega_max, Kp_w, Ki_w, T_max, k_T, I_max,
                 Kp_i, Ki_i, V_dc, T_s):
    """One control period from sampled measurements.

    ``sin_e, cos_e``: sine and cosine of the electrical angle ``p*theta_m``.
    Returns ``(v_a, v_b, v_c, T_ref, int_e, int_w, int_d, int_q)``: phase
    voltage references [V], torque reference [N m] and the new integrals.
    """
    # position PID (derivative on the measurement) -> speed reference
    e = theta_ref - theta_m
    w_ref, int_e = pi_step(e, int_e, Kp, Ki, omega_max, T_s)
    w_ref = _sat(w_ref - Kd * omega_m, omega_max)
    # speed PI -> torque reference
    T_ref, int_w = pi_step(w_ref - omega_m, int_w, Kp_w, Ki_w, T_max, T_s)
    i_q_ref = _sat(T_ref / k_T, I_max)
    # dq current PI at the electrical angle
    i_al, i_be = clarke(i_a, i_b, i_c)
    i_d, i_q = park(i_al, i_be, sin_e, cos_e)
    v_lim = V_dc / math.sqrt(3.0)
    v_d, int_d = pi_step(-i_d, int_d, Kp_i, Ki_i, v_lim, T_s)
    v_q, int_q = pi_step(i_q_ref - i_q, int_q, Kp_i, Ki_i, v_lim, T_s)
    v_q = v_q + (k_T / 1.5) * omega_m
    # keep the voltage vector inside the linear modulation range
    mag = math.sqrt(v_d * v_d + v_q * v_q)
    if mag > v_lim:
        v_d *= v_lim / mag
        v_q *= v_lim / mag
    v_al, v_be = inv_park(v_d, v_q, sin_e, cos_e)
    v_a, v_b, v_c = inv_clarke(v_al, v_be)
    return v_a, v_b, v_c, T_ref, int_e, int_w, int_d, int_q
