"""Transmission of the reference *plant*: Stribeck dry friction and a compliant,
damped backlash contact.

The monitoring model (:mod:`emaphm.models.mechanics`) has Borello's two-level
friction and steps the same compliant contact at its coarse step (or, where that
step does not resolve the contact, a rigid one). The plant the diagnosis is
judged on has physics the MM lacks: the Stribeck drop, and the contact resolved
at the plant's fine step with the unit's own stiffness (:mod:`emaphm.units`).

Dry friction with a Stribeck drop (motor side)
----------------------------------------------
At rest, Borello's stick/breakaway with the static level ``FSJ``: a body under
a torque ``|T_act| <= FSJ`` stays exactly still, above it breaks away net of
``FSJ``. Moving::

    T_f = sign(omega) (FDJ + (FSJ - FDJ) exp(-(omega / omega_s)^2))

so friction falls continuously from ``FSJ`` at breakaway to ``FDJ`` at speeds
well above the Stribeck velocity ``omega_s``. A speed that would cross zero
inside a step is set to zero (the body stops; the static branch decides the
next step), as in Borello's algorithm.

Backlash with a compliant contact
---------------------------------
Motor (``J_m``, ``C_m``, the friction above) and load (``J_l``, ``C_l``, the
load torque ``T_l``) are two bodies. Inside a dead band of total width
``backlash`` on the angle difference ``gap = theta_m - theta_l`` no torque
passes; beyond the edge the penetration ``delta = gap - backlash/2`` (or
``gap + backlash/2`` on the other side) loads a spring-damper::

    T_c = K_c delta + D_c d(gap)/dt,   clipped so that it never pulls:
    T_c >= 0 for delta > 0,  T_c <= 0 for delta < 0

(the damper would otherwise make the contact adhesive while the bodies part).
``T_c`` drives the load and brakes the motor::

    J_m domega_m/dt = T_m - C_m omega_m - T_c - T_f(omega_m)
    J_l domega_l/dt = T_c - C_l omega_l - T_l

Time stepping: symplectic (semi-implicit) Euler: speeds from the torques at
the step start, angles from the new speeds. It keeps the contact oscillation
bounded for ``omega_n dt < 2`` even without damping (an explicit Euler with
trapezoidal angles would let it grow); first order in ``dt``. With the
defaults (``K_c = 4000 N m/rad``, ``J_m = J_l = 7.7e-4 kg m^2``) the contact
resonance is near 500 Hz: ``omega_n dt`` is about 3e-3 at the plant's 1 us step.

Parameters (units): angles [rad], speeds [rad/s], torques [N m], ``J`` [kg m^2],
``C`` [N m s/rad], ``omega_s`` [rad/s], ``K_c`` [N m/rad], ``D_c`` [N m s/rad],
``dt`` [s].
"""

import math

from ._jit import jit
from .mechanics import contact_torque

__all__ = ["stribeck_torque", "stribeck_friction_step", "contact_torque", "plant_step"]


@jit
def stribeck_torque(omega, FSJ, FDJ, omega_s):
    """Magnitude of the sliding friction torque at speed ``omega`` [N m]."""
    x = omega / omega_s
    return FDJ + (FSJ - FDJ) * math.exp(-x * x)


@jit
def stribeck_friction_step(omega, T_act, FSJ, FDJ, omega_s, J, dt):
    """Speed after one explicit step of a body with inertia ``J`` under Stribeck
    dry friction; ``T_act`` is every torque on the body except dry friction.

    The algorithm of :func:`emaphm.models.mechanics.friction_step` with the
    sliding level ``FDJ`` replaced by :func:`stribeck_torque`.
    """
    if omega != 0.0:                                   # moving
        sgn = 1.0 if omega > 0.0 else -1.0
        w = omega + dt * (T_act - sgn * stribeck_torque(omega, FSJ, FDJ, omega_s)) / J
        if w * sgn <= 0.0:                             # must stop inside the step
            return 0.0
        return w
    if abs(T_act) <= FSJ:                              # stuck and stays stuck
        return 0.0
    sgn = 1.0 if T_act > 0.0 else -1.0                 # breaks away
    return dt * (T_act - FSJ * sgn) / J


@jit
def plant_step(theta_m, omega_m, theta_l, omega_l, T_m, T_l,
               J_m, C_m, FSJ, FDJ, omega_s, J_l, C_l, backlash, K_c, D_c, dt):
    """Advance motor and load over one step (symplectic Euler).

    ``T_m`` motor (air-gap) torque, ``T_l`` external load torque, both held
    over the step. Returns ``(theta_m, omega_m, theta_l, omega_l)``.
    """
    T_c = contact_torque(theta_m - theta_l, omega_m - omega_l, backlash, K_c, D_c)
    w_m = stribeck_friction_step(omega_m, T_m - C_m * omega_m - T_c, FSJ, FDJ, omega_s, J_m, dt)
    w_l = omega_l + dt * (T_c - C_l * omega_l - T_l) / J_l
    return theta_m + dt * w_m, w_m, theta_l + dt * w_l, w_l
