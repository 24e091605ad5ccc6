"""Three-phase star-connected surface PMSM (paper Eq. 2, 5 and 6).

Phase ``j`` (a, b, c = 0, 1, 2) obeys, with ``v_jN`` the inverter leg voltage
against the DC link's negative rail and ``v_n`` the floating star point,

    v_jN - v_n - c_j(theta_m) * omega_m = R_j i_j + L_j di_j/dt,    sum_j i_j = 0

with the back-EMF coefficient (Eq. 2, eccentricity on the mechanical angle)

    c_j = c0_j * sin(p theta_m - phi_j) * (1 + ecc * cos(theta_m + ecc_phase + psi_j))
    phi_j = 0, 2 pi/3, 4 pi/3        psi_j = 0, +2 pi/3, -2 pi/3

and torque ``T_m = sum_j c_j i_j`` (Eq. 6). Balanced currents
``i_j = I sin(p theta_m - phi_j)`` give ``T_m = 1.5 c0 I``.

Time stepping: each phase's RL branch is advanced with its exact exponential
response to a voltage held over the step, and the star point voltage ``v_n`` is
the one that keeps ``sum_j i_j = 0`` at the end of the step. The update is
unconditionally stable for any ``R_j, L_j > 0`` and step (a short circuit can
make ``L_j/R_j`` much shorter than the step), first order in the step through
the back-EMF and star point held over it.
"""

import math

from ._jit import jit

TWO_PI_3 = 2.0 * math.pi / 3.0


COS_2PI_3 = -0.5
SIN_2PI_3 = 0.5 * math.sqrt(3.0)


@jit
def back_emf_coeffs(theta_m, sin_e, cos_e, c0_a, c0_b, c0_c, ecc, ecc_phase):
    """Per-phase back-EMF coefficients c_a, c_b, c_c [V s/rad].

    ``theta_m`` motor angle [rad]; ``sin_e, cos_e`` sine and cosine of the
    electrical angle ``p*theta_m`` (computed once per step by the caller, the
    other phases follow by rotation).
    """
    s_a = sin_e
    s_b = sin_e * COS_2PI_3 - cos_e * SIN_2PI_3     # sin(theta_e - 2 pi/3)
    s_c = sin_e * COS_2PI_3 + cos_e * SIN_2PI_3     # sin(theta_e + 2 pi/3)
    if ecc == 0.0:
        return c0_a * s_a, c0_b * s_b, c0_c * s_c
    g = theta_m + ecc_phase
    cg = math.cos(g)
    sg = math.sin(g)
    m_a = 1.0 + ecc * cg
    m_b = 1.0 + ecc * (cg * COS_2PI_3 - sg * SIN_2PI_3)  # cos(g + 2 pi/3)
    m_c = 1.0 + ecc * (cg * COS_2PI_3 + sg * SIN_2PI_3)  # cos(g - 2 pi/3)
    return c0_a * s_a * m_a, c0_b * s_b * m_b, c0_c * s_c * m_c


@jit
def rl_coeffs(R, L, dt):
    """Exact step of one RL branch: i' = a i + h u for a voltage u held over dt.

    Returns ``a = exp(-dt R/L)`` [-] and ``h = (1 - a)/R`` [A/V].
    """
    x = dt * R / L
    a = math.exp(-x)
    h = -math.expm1(-x) / R
    return a, h


@jit
def phase_step(i_a, i_b, i_c, v_a, v_b, v_c, e_a, e_b, e_c,
               a_a, a_b, a_c, h_a, h_b, h_c):
    """Advance the three phase currents over one step.

    ``v_*`` leg voltages [V], ``e_*`` back-EMFs [V], ``a_*, h_*`` from
    :func:`rl_coeffs`. Returns the new currents [A] and the star point voltage [V].
    """
    free = a_a * i_a + a_b * i_b + a_c * i_c + h_a * (v_a - e_a) + h_b * (v_b - e_b) + h_c * (v_c - e_c)
    v_n = free / (h_a + h_b + h_c)
    return (a_a * i_a + h_a * (v_a - e_a - v_n),
            a_b * i_b + h_b * (v_b - e_b - v_n),
            a_c * i_c + h_c * (v_c - e_c - v_n),
            v_n)


@jit
def torque(i_a, i_b, i_c, c_a, c_b, c_c):
    """Electromagnetic torque T_m = sum_j c_j i_j [N m] (Eq. 6)."""
    return c_a * i_a + c_b * i_b + c_c * i_c
