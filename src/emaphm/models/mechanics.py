"""Transmission dynamics (paper Eq. 7) with dry friction and backlash, as the
monitoring model integrates them.

Two bodies referred to the motor shaft: the motor side (rotor and the
transmission's moving parts, inertia ``J_m``, viscous ``C_m``, dry friction
``FSJ``/``FDJ``) and the load (``J_l``, ``C_l``, external torque ``T_l``),
coupled through a dead band of total width ``backlash``. Inside the gap the
motor drives only its own inertia. Beyond it the teeth touch:

* **compliant contact** (``K_c > 0``): the penetration loads the gear train's
  torsional stiffness ``K_c`` [N m/rad] and damping ``D_c`` [N m s/rad]
  (:func:`contact_torque`, a spring-damper that pushes but never pulls), a
  two-mass resonance ``omega_c = sqrt(K_c (J_m + J_l) / (J_m J_l))``. Stepped
  by symplectic (semi-implicit) Euler: speeds from the torques at the step
  start, angles from the new speeds; bounded for ``omega_c dt < 2``.
* **rigid contact** (``K_c = 0``, the paper's idealisation): an inelastic impact
  that conserves momentum, after which the bodies move as one for as long as
  the contact pushes. :func:`emaphm.models.layout.pack_shared` packs
  ``K_c = 0`` when the step does not resolve the resonance
  (``omega_c dt > CONTACT_RESOLVED``): a contact that stiff is rigid at that step.

Dry friction follows Borello's discontinuous Coulomb algorithm (stick/slip
with static and dynamic levels, a velocity that would cross zero inside a
step is set to zero), not a smoothed sign function: a body under a torque
below ``FSJ`` stays exactly still. The reference plant
(:mod:`emaphm.models.plant_mechanics`) adds a Stribeck drop the monitoring
model lacks.
"""

from ._jit import jit

__all__ = ["friction_step", "contact_torque", "transmission_step", "CONTACT_RESOLVED",
           "stribeck_factor"]

#: Largest ``omega_c dt`` [-] at which the monitoring model steps the backlash contact as
#: a spring-damper (symplectic Euler is bounded below 2; at 1 its frequency is 4 % off,
#: at the preset's 0.4 less than 1 %); above it the contact is rigid.
CONTACT_RESOLVED = 1.0


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
def stribeck_factor(omega, omega_s):
    """``exp(-(omega / omega_s)^2)`` [-], the share of the static-over-dynamic friction
    left at speed ``omega`` (the Stribeck drop), 0 for ``omega_s <= 0`` (Borello's two
    levels): ``FDJ + (FSJ - FDJ) stribeck_factor`` is the sliding friction. Without a
    branch or libm, so that it runs in vector lanes: ``e^-u = (e^(-u/64))^64``, the inner
    exponential by its Taylor series to the 12th power (``u/64 <= 0.625``: relative error
    below 1e-13 before the squarings, 1e-11 after), ``u`` capped at 40 (``e^-40 = 4e-18``).
    """
    x = omega / max(omega_s, 1e-300)
    u = min(x * x, 40.0) * (1.0 / 64.0)
    # e^-u by Horner, terms to u^12 / 12!
    e = 1.0 + u * (-1.0 + u * (1.0 / 2.0 + u * (-1.0 / 6.0 + u * (1.0 / 24.0 + u * (
        -1.0 / 120.0 + u * (1.0 / 720.0 + u * (-1.0 / 5040.0 + u * (1.0 / 40320.0 + u * (
            -1.0 / 362880.0 + u * (1.0 / 3628800.0 + u * (-1.0 / 39916800.0
                                                          + u / 479001600.0)))))))))))
    for _ in range(6):
        e = e * e
    return e if omega_s > 0.0 else 0.0


@jit
def contact_torque(gap, gap_rate, backlash, K_c, D_c):
    """Torque the motor side passes to the load through the backlash [N m].

    ``gap = theta_m - theta_l`` [rad], ``gap_rate = omega_m - omega_l`` [rad/s].
    Zero inside the dead band ``|gap| <= backlash/2``; beyond, a spring-damper
    on the penetration that pushes but never pulls (the damper would otherwise
    make the contact adhesive while the bodies part).
    """
    half = 0.5 * backlash
    if gap > half:
        return max(K_c * (gap - half) + D_c * gap_rate, 0.0)
    if gap < -half:
        return min(K_c * (gap + half) + D_c * gap_rate, 0.0)
    return 0.0


@jit
def transmission_step(theta_m, omega_m, theta_l, omega_l, T_m, T_l,
                      J_m, C_m, FSJ, FDJ, J_l, C_l, backlash, K_c, D_c, dt):
    """Advance motor and load over one step; ``T_m``, ``T_l`` held over it.

    Returns ``(theta_m, omega_m, theta_l, omega_l)``.

    ``K_c > 0``: compliant contact by symplectic Euler (see the module doc).
    ``K_c = 0``: rigid contact. Speeds by explicit Euler with Borello friction,
    positions by the trapezoid rule on the speeds; first each body moves
    freely, and if that would close the gap the two move as one body from
    their common (momentum-conserving) speed with the load on the gap's edge.
    """
    if K_c > 0.0:
        T_c = contact_torque(theta_m - theta_l, omega_m - omega_l, backlash, K_c, D_c)
        w_m = friction_step(omega_m, T_m - C_m * omega_m - T_c, FSJ, FDJ, J_m, dt)
        w_l = omega_l + dt * (T_c - C_l * omega_l - T_l) / J_l
        return theta_m + dt * w_m, w_m, theta_l + dt * w_l, w_l
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
