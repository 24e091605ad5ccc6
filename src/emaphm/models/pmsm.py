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
from .windings import Q as _Q

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


# ---- the winding circuit of emaphm.models.windings, stepped exactly ----------------------
#
# The monitoring model advances the reduced winding system ``L_r dz/dt = -R_r z + w`` of
# :mod:`emaphm.models.windings` (``z = [y_alpha, y_beta, f_a, f_b, f_c]``, phase currents
# ``i_abc = Q y``, fault-loop currents ``f``) with its exact step for inputs held over the
# step, ``z' = Phi z + Gamma w`` (:func:`emaphm.models.windings.zoh`). With
# ``sigma = 1, mu = 0`` (the paper's fault model) the loops stay at zero and this is the
# three RL branches above with the star point solved exactly instead of held.

#: Entries of ``windings.Q`` (i_abc = Q y): phase a has no beta part.
QA_AL = float(_Q[0, 0])
QB_AL = float(_Q[1, 0])
QB_BE = float(_Q[1, 1])
QC_AL = float(_Q[2, 0])
QC_BE = float(_Q[2, 1])


@jit
def winding_input(u_a, u_b, u_c, e_a, e_b, e_c, mu_a, mu_b, mu_c):
    """Input ``w = [Q^T (u - e), mu_j e_j]`` [V] of the reduced winding system.

    ``u_*`` leg voltages [V] (the star point drops out), ``e_* = c_* omega_m`` back-EMFs
    [V], ``mu_*`` shorted fractions [-]: the shorted turns carry ``mu_j e_j``, which
    drives the fault loop.
    """
    d_a = u_a - e_a
    d_b = u_b - e_b
    d_c = u_c - e_c
    return (QA_AL * d_a + QB_AL * d_b + QC_AL * d_c, QB_BE * d_b + QC_BE * d_c,
            mu_a * e_a, mu_b * e_b, mu_c * e_c)


@jit
def phase_currents(y_al, y_be):
    """Phase currents ``i_abc = Q y`` [A] from the zero-sum coordinates ``y`` [A]."""
    return QA_AL * y_al, QB_AL * y_al + QB_BE * y_be, QC_AL * y_al + QC_BE * y_be


@jit
def winding_step(z0, z1, z2, z3, z4, w0, w1, w2, w3, w4, Phi, Gam):
    """Exact step ``z' = Phi z + Gamma w`` of the reduced winding system.

    ``z`` [A] state, ``w`` [V] input held over the step (:func:`winding_input`),
    ``Phi`` [-] and ``Gam`` [A/V] the 25 entries of the 5 x 5 matrices row by row
    (tuples, or arrays of candidates' columns), from :func:`emaphm.models.windings.zoh`.
    """
    return ((Phi[0] * z0 + Phi[1] * z1 + Phi[2] * z2 + Phi[3] * z3 + Phi[4] * z4)
            + (Gam[0] * w0 + Gam[1] * w1 + Gam[2] * w2 + Gam[3] * w3 + Gam[4] * w4),
            (Phi[5] * z0 + Phi[6] * z1 + Phi[7] * z2 + Phi[8] * z3 + Phi[9] * z4)
            + (Gam[5] * w0 + Gam[6] * w1 + Gam[7] * w2 + Gam[8] * w3 + Gam[9] * w4),
            (Phi[10] * z0 + Phi[11] * z1 + Phi[12] * z2 + Phi[13] * z3 + Phi[14] * z4)
            + (Gam[10] * w0 + Gam[11] * w1 + Gam[12] * w2 + Gam[13] * w3 + Gam[14] * w4),
            (Phi[15] * z0 + Phi[16] * z1 + Phi[17] * z2 + Phi[18] * z3 + Phi[19] * z4)
            + (Gam[15] * w0 + Gam[16] * w1 + Gam[17] * w2 + Gam[18] * w3 + Gam[19] * w4),
            (Phi[20] * z0 + Phi[21] * z1 + Phi[22] * z2 + Phi[23] * z3 + Phi[24] * z4)
            + (Gam[20] * w0 + Gam[21] * w1 + Gam[22] * w2 + Gam[23] * w3 + Gam[24] * w4))


@jit
def torque_loops(i_a, i_b, i_c, f_a, f_b, f_c, c_a, c_b, c_c, mu_a, mu_b, mu_c):
    """Torque with fault loops ``T_m = sum_j c_j (i_j - mu_j f_j)`` [N m]: the loop's
    MMF opposes the phase's (equal to :func:`torque` without loops, ``f = 0``)."""
    return c_a * (i_a - mu_a * f_a) + c_b * (i_b - mu_b * f_b) + c_c * (i_c - mu_c * f_c)
