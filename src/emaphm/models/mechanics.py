"""Transmission dynamics (paper Eq. 7) with dry friction and backlash.

Two rigid bodies referred to the motor shaft: the motor side (rotor and the
transmission's moving parts, inertia ``J_m``, viscous ``C_m``, dry friction
``FSJ``/``FDJ``) and the load (``J_l``, ``C_l``, external torque ``T_l``),
coupled through a dead band of total width ``backlash``. Inside the gap the
motor drives only its own inertia; at contact the bodies move together
(inelastic impact that conserves momentum) for as long as the contact pushes.

Dry friction follows Borello's discontinuous Coulomb algorithm (stick/slip
with static and dynamic levels, a velocity that would cross zero inside a
step is set to zero), not a smoothed sign function: a body under a torque
below ``FSJ`` stays exactly still.
"""

from ._jit import jit


@jit
def friction_step(omega, T_act, FSJ, FDJ, J, dt):
    """Speed after one step of a body with inertia J under Borello dry friction.

    ``T_act`` is every torque on the body except dry friction [N m].
    """
    if omega != 0.0:                                   # moving
        sgn = 1.0 if omega > 0.0 else -1.0
        w = omega + dt * (T_act - FDJ * sgn) / J
        if w * sgn <= 0.0:                             # must stop inside the step
            return 0.0
        return w
    if abs(T_act) <= FSJ:                              # stuck and stays stuck
        return 0.0
    sgn = 1.0 if T_act > 0.0 else -1.0                 # breaks away
    return dt * (T_act - FSJ * sgn) / J


@jit
def transmission_step(theta_m, omega_m, theta_l, omega_l, T_m, T_l,
                      J_m, C_m, FSJ, FDJ, J_l, C_l, backlash, dt):
    """Advance motor and load over one step.

    Speeds by explicit Euler with Borello friction, positions by the
    trapezoid rule on the speeds (second order on smooth motion).

    Returns ``(theta_m, omega_m, theta_l, omega_l)``. First each body moves
    freely; if that would close the gap, the two move as one body from their
    common (momentum-conserving) speed and the load sits on the gap's edge.
    """
    w_m = friction_step(omega_m, T_m - C_m * omega_m, FSJ, FDJ, J_m, dt)
    w_l = omega_l + dt * (-T_l - C_l * omega_l) / J_l
    th_m = theta_m + 0.5 * dt * (w_m + omega_m)
    th_l = theta_l + 0.5 * dt * (w_l + omega_l)
    half = 0.5 * backlash
    gap = th_m - th_l
    if -half <= gap <= half:
        return th_m, w_m, th_l, w_l
    side = 1.0 if gap > 0.0 else -1.0
    J = J_m + J_l
    w0 = (J_m * omega_m + J_l * omega_l) / J
    w = friction_step(w0, T_m - T_l - (C_m + C_l) * w0, FSJ, FDJ, J, dt)
    th_m = theta_m + 0.5 * dt * (w + omega_m)
    return th_m, w, th_m - side * half, w
