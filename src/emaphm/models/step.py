"""The monitoring model's step, once: what one candidate does in one control period.

Every implementation of the monitoring model runs these functions and nothing else of
its own physics:

* :func:`control` -- the fitness term of the control instant, the drive's overcurrent
  trip, the cascade controller (:func:`~emaphm.models.controller.control_step`) and the
  averaged inverter (:func:`~emaphm.models.inverter.modulate`);
* :func:`substep` -- one integration step of the plant: back-EMF (:func:`back_emf`),
  winding circuit (:func:`~emaphm.models.pmsm.winding_input`,
  :func:`~emaphm.models.pmsm.winding_step`), torque with fault loops and the
  transmission (:func:`~emaphm.models.mechanics.transmission_step`);
* :func:`healthy` -- the physical range a candidate must stay in.

The sines and cosines come from outside (the electrical angle and, with eccentricity, the
mechanical angle plus its phase), so that the same step runs on libm's trigonometry (the
scalar kernel and the readable loop of :mod:`emaphm.models.monitoring`) and on
:func:`sincos` (the SIMD kernel of :mod:`emaphm.models.monitoring_simd`, where libm
would stop the vectoriser). With the same sines both give the same bits: the tests run
the scalar kernel on :func:`sincos` and compare bit for bit.

The functions are written without branches that stay branches (choices by
:func:`select`), so LLVM vectorises them in the SIMD kernel's lanes. Each exists twice,
from the same source: as plain Python (the readable loop, the test oracle) and compiled
for Numba-IR inlining (``*_inline``, :func:`inlined`), with the physics functions it
calls inlined too.
"""

from __future__ import annotations

import types

from numba import njit, types as nbtypes
from numba.extending import intrinsic

from . import controller as _controller
from . import inverter as _inverter
from . import mechanics as _mechanics
from . import pmsm as _pmsm
from ._monitoring_common import I_DIVERGED, OMEGA_DIVERGED
from .controller import N_STATE as N_CTL_STATE
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_ECC, C_FDJ, C_FSJ, C_GAMMA, C_KP,
                     C_OMEGA_S, C_V_DT,
                     C_MU_A, C_MU_B, C_MU_C, C_PHI, C_PHI_END, C_GAMMA_END, C_T0)
from .pmsm import COS_2PI_3, SIN_2PI_3

__all__ = ["select", "llvm_select", "sincos", "TRIG_LIMIT", "back_emf", "overcurrent", "control", "substep",
           "healthy", "inline", "inlined", "control_inline", "substep_inline", "sincos_inline",
           "healthy_inline", "X_FIELDS", "N_X", "Q_FIELDS", "N_Q", "PERIOD_FIELDS", "initial_x",
           "initial_q", "initial_x_inline", "row_reader", "row_writer", "vector_reader", "lane_reader",
           "lane_writer", "keep", "control_plain_inline", "plain_inline", "substep_ideal_inline"]

#: Compile a function into its caller at Numba IR level. LLVM's inliner leaves the larger
#: physics functions as calls, and every call returns Numba's status code, whose check is
#: an early exit from the lane loop; the vectoriser gives up on both. IEEE division
#: (``error_model="numpy"``): a ZeroDivisionError check is such an exit too (inlined into
#: a kernel, a function takes the kernel's error model).
inline = njit(nogil=True, inline="always", error_model="numpy")


@intrinsic
def llvm_select(typingctx, cond, a, b):
    """``a if cond else b`` as one LLVM ``select`` (both sides evaluated, no branch).

    Numba compiles a conditional expression to a branch; InstCombine then sinks the
    computation of the taken side into it, and the vectoriser may fail to flatten it.
    """
    if not (isinstance(cond, nbtypes.Boolean) and isinstance(a, nbtypes.Float)
            and a == b):
        return None
    sig = a(cond, a, b)

    def codegen(context, builder, signature, args):
        return builder.select(args[0], args[1], args[2])

    return sig, codegen


def select(cond, a, b):
    """``a if cond else b``; in the inlined versions of this module's functions an LLVM
    ``select`` (:func:`llvm_select`)."""
    return a if cond else b


def inlined(func, **callees):
    """``func``'s own code compiled for inlining, with the named global callees replaced
    (by their inlined versions) and :func:`select` by the LLVM select."""
    py = getattr(func, "py_func", func)
    g = dict(py.__globals__)
    g["select"] = llvm_select
    g.update(callees)
    return inline(types.FunctionType(py.__code__, g, py.__name__, py.__defaults__,
                                     py.__closure__))


# ---- the physics functions, inlined ------------------------------------------------------

_sat = inlined(_controller._sat)
_clarke = inlined(_inverter.clarke)
_park = inlined(_inverter.park)
_inv_park = inlined(_inverter.inv_park)
_inv_clarke = inlined(_inverter.inv_clarke)
_pi_step = inlined(_controller.pi_step, _sat=_sat)
_pi2_step = inlined(_controller.pi2_step, _sat=_sat)
_lowpass = inlined(_controller._lowpass)
_control_parts = dict(_sat=_sat, pi_step=_pi_step, pi2_step=_pi2_step, clarke=_clarke,
                      park=_park, inv_park=_inv_park, inv_clarke=_inv_clarke)
_option_parts = {name: inlined(getattr(_controller, name)) for name in _controller.PLAIN}
_plain_parts = {name: inline(f) for name, f in _controller.PLAIN.items()}
#: The drive's speed and current loops (:func:`~emaphm.models.controller.speed_loop`,
#: :func:`~emaphm.models.controller.current_loop`), inlined
speed_loop_inline = inlined(_controller.speed_loop, **_control_parts, **_option_parts)
current_loop_inline = inlined(_controller.current_loop, **_control_parts, **_option_parts)
control_step_inline = inlined(_controller.control_step, **_control_parts, **_option_parts,
                              speed_loop=speed_loop_inline, current_loop=current_loop_inline)
#: :func:`~emaphm.models.controller.control_step` of a drive without options
#: (:func:`~emaphm.models.controller.plain`): the same numbers, none of the options' work
control_step_plain_inline = inlined(
    _controller.control_step, **_control_parts, **_plain_parts,
    speed_loop=inlined(_controller.speed_loop, **_control_parts, **_plain_parts),
    current_loop=inlined(_controller.current_loop, **_control_parts, **_plain_parts))
modulate_inline = inlined(_inverter.modulate)
winding_input_inline = inlined(_pmsm.winding_input)
winding_step_inline = inlined(_pmsm.winding_step)
phase_currents_inline = inlined(_pmsm.phase_currents)
torque_loops_inline = inlined(_pmsm.torque_loops)
_friction_step = inlined(_mechanics.friction_step)
_contact_torque = inlined(_mechanics.contact_torque)
transmission_step_inline = inlined(_mechanics.transmission_step, friction_step=_friction_step,
                                   contact_torque=_contact_torque)

# the names the step's source calls (plain Python resolves them to the jitted functions)
control_step = _controller.control_step
feedforward = _controller.feedforward
modulate = _inverter.modulate
winding_input = _pmsm.winding_input
winding_step = _pmsm.winding_step
phase_currents = _pmsm.phase_currents
torque_loops = _pmsm.torque_loops
transmission_step = _mechanics.transmission_step
dead_time_drop = _inverter.dead_time_drop
stribeck_factor = _mechanics.stribeck_factor

# ---- sine and cosine (fdlibm, branch-free) ----------------------------------------------

#: |angle| [rad] up to which :func:`sincos` is within 1 ulp (fdlibm's medium range).
TRIG_LIMIT = 1.0e6

_ROUND = 6755399441055744.0          # 1.5 * 2**52: (x + _ROUND) - _ROUND rounds to an integer
_INVPIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e+00     # first 33 bits of pi/2
_PIO2_1T = 6.07710050650619224932e-11
_PIO2_2 = 6.07710050630396597660e-11     # second 33 bits
_PIO2_2T = 2.02226624879595063154e-21
_PIO2_3 = 2.02226624871116645580e-21     # third 33 bits
_PIO2_3T = 8.47842766036889956997e-32
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11


def sincos(x):
    """``(sin x, cos x)`` within 1 ulp for ``|x| <= TRIG_LIMIT``, NaN for non-finite x.

    fdlibm's algorithm without branches: ``x = n pi/2 + (y0 + y1)`` by a
    three-round Cody-Waite reduction, the kernel polynomials on
    ``[-pi/4, pi/4]``, and the quadrant ``n mod 4`` picked by selects.
    """
    fn = (x * _INVPIO2 + _ROUND) - _ROUND
    r = x - fn * _PIO2_1
    t = r
    w = fn * _PIO2_2
    r = t - w
    w = fn * _PIO2_2T - ((t - r) - w)
    t = r
    w = fn * _PIO2_3
    r = t - w
    w = fn * _PIO2_3T - ((t - r) - w)
    y0 = r - w
    y1 = (r - y0) - w
    z = y0 * y0
    v = z * y0
    rs = _S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))
    ks = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * _S1)
    zz = z * z
    rc = z * (_C1 + z * (_C2 + z * _C3)) + zz * zz * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    w1 = 1.0 - hz
    kc = w1 + (((1.0 - w1) - hz) + (z * rc - y0 * y1))
    # n mod 4 as a float: floor(n/4) = round(n/4 - 3/8) for integer n
    q = fn - 4.0 * (((fn * 0.25 - 0.375) + _ROUND) - _ROUND)
    odd = (q == 1.0) | (q == 3.0)
    a = select(odd, kc, ks)
    b = select(odd, ks, kc)
    s = select(q >= 2.0, -a, a)
    c = select((q == 1.0) | (q == 2.0), -b, b)
    return s, c


# ---- the step -----------------------------------------------------------------------------


def back_emf(s_e, c_e, sg, cg, c0_a, c0_b, c0_c, ecc):
    """Back-EMF coefficients ``c_a, c_b, c_c`` [V s/rad] (Eq. 2) from the sine and cosine
    of the electrical angle ``s_e, c_e`` and of ``theta_m + ecc_phase`` (``sg, cg``; not
    read without eccentricity): :func:`emaphm.models.pmsm.back_emf_coeffs`, the same
    operations, its ``ecc == 0`` branch a select."""
    s_a = s_e
    s_b = s_e * COS_2PI_3 - c_e * SIN_2PI_3
    s_c = s_e * COS_2PI_3 + c_e * SIN_2PI_3
    m_a = 1.0 + ecc * cg
    m_b = 1.0 + ecc * (cg * COS_2PI_3 - sg * SIN_2PI_3)
    m_c = 1.0 + ecc * (cg * COS_2PI_3 + sg * SIN_2PI_3)
    no = ecc == 0.0
    return (select(no, c0_a * s_a, c0_a * s_a * m_a),
            select(no, c0_b * s_b, c0_b * s_b * m_b),
            select(no, c0_c * s_c, c0_c * s_c * m_c))


def overcurrent(i_a, i_b, i_c, I_trip):
    """:func:`emaphm.models.inverter.overcurrent` without the short-circuit ``or`` (a branch
    the vectoriser's if-conversion did not take once jump threading had duplicated the
    trip flag's store)."""
    return (abs(i_a) > I_trip) | (abs(i_b) > I_trip) | (abs(i_c) > I_trip)


# ---- the structures the step takes ---------------------------------------------------------
#
# A candidate's constants are its row of the layout's CP (a tuple, ``c``: read by the
# layout's column numbers); the drive's settings the controller's tuple (``ctl``,
# :data:`emaphm.models.controller.CTL_FIELDS`, the head of the layout's P); its state two
# tuples, the plant's ``x`` and the drive's ``q``. A new column of the physics changes the
# layout and this module; the kernels move the tuples whole.

#: The plant's state of a candidate: motor and load angle [rad] and speed [rad/s], the
#: winding circuit's ``z`` [A] and its phase currents ``i = Q y`` [A].
X_FIELDS = ("theta_m", "omega_m", "theta_l", "omega_l", "z0", "z1", "z2", "z3", "z4",
            "i_a", "i_b", "i_c")
N_X = len(X_FIELDS)
(X_THM, X_WM, X_THL, X_WL, X_Z0, X_Z1, X_Z2, X_Z3, X_Z4, X_IA, X_IB, X_IC) = range(N_X)
#: The drive's state of a candidate: tripped (1.0) or not, the Eq. 4 sum so far, then the
#: controller's state (:data:`emaphm.models.controller.STATE_FIELDS`).
Q_FIELDS = ("trip", "fit") + _controller.STATE_FIELDS
N_Q = len(Q_FIELDS)
#: What a control period brings: the target currents [A] and their Eq. 4 weights, the
#: position command [rad] and its feed-forward terms [rad/s, N m]
#: (:func:`emaphm.models.controller.feedforward`).
PERIOD_FIELDS = ("t_a", "t_b", "t_c", "w_a", "w_b", "w_c", "ref", "omega_ff", "T_ff")


def initial_x(theta0):
    """The plant at rest at the angle ``theta0`` [rad], no current."""
    return (theta0, 0.0, theta0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def initial_q():
    """The drive before the first period: not tripped, nothing summed, every integral,
    filter and held voltage at zero."""
    return tuple(0.0 for _ in Q_FIELDS)


def row_reader(n, name="read_row"):
    """A function ``f(A, r, *index)`` returning ``(A[*index_head, r + 0, *index_tail], ...)``
    as a tuple of ``n`` scalars: compiled for inlining, it moves a structure of the step
    between the kernels' arrays and the step without a loop (a tuple's length must be
    known when it is compiled). ``row_reader(n)`` reads ``A[i, r + e]`` (``f(A, r, i)``);
    :func:`lane_reader` reads the SIMD kernel's ``B[b, r + e, l]``."""
    body = ", ".join(f"A[i, r + {e}]" for e in range(n))
    return _compiled(f"def {name}(A, r, i):\n    return ({body},)\n", name)


def vector_reader(n, name="read_vector"):
    """A function ``f(A, r)`` returning ``(A[r + 0], ..., A[r + n - 1])``."""
    body = ", ".join(f"A[r + {e}]" for e in range(n))
    return _compiled(f"def {name}(A, r):\n    return ({body},)\n", name)


def lane_reader(n, name="read_lane"):
    """A function ``f(B, r, b, l)`` returning ``(B[b, r + 0, l], ..., B[b, r + n - 1, l])``."""
    body = ", ".join(f"B[b, r + {e}, l]" for e in range(n))
    return _compiled(f"def {name}(B, r, b, l):\n    return ({body},)\n", name)


def row_writer(n, name="write_row"):
    """A function ``f(A, r, i, x)`` storing the ``n`` scalars of the tuple ``x`` at
    ``A[i, r + e]``."""
    body = "".join(f"    A[i, r + {e}] = x[{e}]\n" for e in range(n))
    return _compiled(f"def {name}(A, r, i, x):\n{body}", name)


def lane_writer(n, name="write_lane"):
    """A function ``f(B, r, b, l, x)`` storing the tuple ``x`` at ``B[b, r + e, l]``."""
    body = "".join(f"    B[b, r + {e}, l] = x[{e}]\n" for e in range(n))
    return _compiled(f"def {name}(B, r, b, l, x):\n{body}", name)


def _compiled(source, name):
    return inline(_python(source, name))


def _python(source, name, **namespace):
    """The function ``name`` that ``source`` defines, with ``namespace`` as its globals."""
    exec(compile(source, f"<emaphm.models.step.{name}>", "exec"), namespace)
    return namespace[name]


#: ``keep(tripped, old, new)``: the controller's state ``old`` where the drive tripped,
#: else ``new``, element by element (selects, no branch).
keep = _python("def keep(tripped, old, new):\n    return ("
               + ", ".join(f"select(tripped, old[{e}], new[{e}])" for e in range(N_CTL_STATE))
               + ",)\n", "keep", select=select)


def control(x, q, c, ctl, I_trip, period, s_e, c_e):
    """Fitness term, overcurrent trip, controller and modulation of one candidate.

    ``x`` its plant state (:data:`X_FIELDS`), ``q`` its drive state (:data:`Q_FIELDS`),
    ``c`` its constants (its row of the layout's CP), ``ctl`` the drive's settings
    (:data:`emaphm.models.controller.CTL_FIELDS`), ``I_trip`` [A] the overcurrent trip,
    ``period`` (:data:`PERIOD_FIELDS`): target currents, Eq. 4 weights (0 without a
    target) and the position command with its feed-forward terms. Returns ``(q, u_a, u_b, u_c)``: the new drive state
    and the leg voltages ``u = d V_dc`` [V] of the period (0 V and the controller frozen
    once tripped: active short circuit, controller stopped).
    """
    ta, tb, tc, wa, wb, wc, ref, w_ff, T_ff = period
    thm, wm = x[X_THM], x[X_WM]
    ia, ib, ic = x[X_IA], x[X_IB], x[X_IC]
    trip, fit = q[0], q[1]
    # unconditional (a conditional store stops the vectoriser): without a target the
    # weights are 0 and so is the term, but for a non-finite current, which diverges
    da = ia - ta
    db = ib - tb
    dc = ic - tc
    fit = fit + (wa * da * da + wb * db * db + wc * dc * dc)
    tripped = (trip != 0.0) | overcurrent(ia, ib, ic, I_trip)
    old = q[2:]
    v_a, v_b, v_c, _, new = control_step((ref, w_ff, T_ff), thm, wm, ia, ib, ic, s_e, c_e, old,
                                         c[C_KP], ctl)
    V_dc = ctl[_controller.CTL_V_DC]
    d_a, d_b, d_c = modulate(v_a, v_b, v_c, V_dc)
    return ((select(tripped, 1.0, 0.0), fit) + keep(tripped, old, new),
            select(tripped, 0.0, d_a) * V_dc, select(tripped, 0.0, d_b) * V_dc,
            select(tripped, 0.0, d_c) * V_dc)


def substep(x, c, mech, s_e, c_e, s_g, c_g, u_a, u_b, u_c):
    """One integration step of the plant of one candidate: back-EMF, winding circuit,
    transmission.

    ``x`` its plant state (:data:`X_FIELDS`), ``c`` its constants (its CP row: back-EMF
    coefficients, shorted fractions, eccentricity, the winding step's ``Phi`` and
    ``Gamma``, friction with its Stribeck speed, backlash, its own load torque ``T_0`` [N m]
    and what its legs lose to dead time) beside the profile's ``T_l`` in ``mech = (T_l, J_m,
    C_m, J_l, C_l, K_c, D_c, dt, 1/i_0)``; the sines and cosines of the electrical angle and
    of ``theta_m + ecc_phase``; the leg voltages [V].
    Returns ``(x, torque at the start of the step)``.

    The sliding friction is ``FDJ + (FSJ - FDJ) exp(-(omega_m/omega_s)^2)`` at the step's
    start speed (:func:`~emaphm.models.mechanics.stribeck_factor`, branch-free: it runs in
    the vector lanes; ``omega_s = 0`` is Borello's two levels, exactly ``FDJ``).
    """
    T_l, J_m, C_m, J_l, C_l, K_c, D_c, dt, inv_i0 = mech
    thm, wm, thl, wl, z0, z1, z2, z3, z4, ia, ib, ic = x
    mu_a, mu_b, mu_c = c[C_MU_A], c[C_MU_B], c[C_MU_C]
    ca, cb, cc = back_emf(s_e, c_e, s_g, c_g, c[C_C0_A], c[C_C0_B], c[C_C0_C], c[C_ECC])
    tq = torque_loops(ia, ib, ic, z2, z3, z4, ca, cb, cc, mu_a, mu_b, mu_c)
    V = c[C_V_DT]
    w0, w1, w2, w3, w4 = winding_input(u_a - dead_time_drop(ia, V, inv_i0),
                                       u_b - dead_time_drop(ib, V, inv_i0),
                                       u_c - dead_time_drop(ic, V, inv_i0), ca * wm, cb * wm,
                                       cc * wm, mu_a, mu_b, mu_c)
    z0, z1, z2, z3, z4 = winding_step(z0, z1, z2, z3, z4, w0, w1, w2, w3, w4,
                                      c[C_PHI:C_PHI_END], c[C_GAMMA:C_GAMMA_END])
    ja, jb, jc = phase_currents(z0, z1)
    # the mechanics see the step's mean torque (trapezoid): second order in the fast
    # current transients of the coarse step
    T_m = 0.5 * (tq + torque_loops(ja, jb, jc, z2, z3, z4, ca, cb, cc, mu_a, mu_b, mu_c))
    FSJ, FDJ = c[C_FSJ], c[C_FDJ]
    F_d = FDJ + (FSJ - FDJ) * stribeck_factor(wm, c[C_OMEGA_S])
    thm, wm, thl, wl = transmission_step(thm, wm, thl, wl, T_m, T_l + c[C_T0], J_m, C_m,
                                         FSJ, F_d, J_l, C_l, c[C_BACKLASH], K_c, D_c, dt)
    return (thm, wm, thl, wl, z0, z1, z2, z3, z4, ja, jb, jc), tq


def healthy(ia, ib, ic, wm, thm):
    """True while a candidate stays in the physical range (currents below
    :data:`~emaphm.models._monitoring_common.I_DIVERGED`, speed below
    :data:`~emaphm.models._monitoring_common.OMEGA_DIVERGED`, angle below 1e9 rad, all
    finite); a candidate that leaves it is frozen with infinite fitness."""
    return ((abs(ia) < I_DIVERGED) & (abs(ib) < I_DIVERGED) & (abs(ic) < I_DIVERGED)
            & (abs(wm) < OMEGA_DIVERGED) & (abs(thm) < 1e9))


# ---- the same, compiled for inlining into the kernels --------------------------------------

sincos_inline = inlined(sincos)
overcurrent_inline = inlined(overcurrent)
back_emf_inline = inlined(back_emf)
healthy_inline = inlined(healthy)
keep_inline = inlined(keep)
initial_x_inline = inlined(initial_x)
control_inline = inlined(control, overcurrent=overcurrent_inline, keep=keep_inline,
                         control_step=control_step_inline, modulate=modulate_inline)
#: :func:`control` of a drive without options (:func:`emaphm.models.controller.plain`)
control_plain_inline = inlined(control, overcurrent=overcurrent_inline, keep=keep_inline,
                               control_step=control_step_plain_inline, modulate=modulate_inline)
plain_inline = inlined(_controller.plain)
_substep_parts = dict(back_emf=back_emf_inline, torque_loops=torque_loops_inline,
                      winding_input=winding_input_inline, winding_step=winding_step_inline,
                      phase_currents=phase_currents_inline,
                      transmission_step=transmission_step_inline)
substep_inline = inlined(substep, dead_time_drop=inlined(_inverter.dead_time_drop),
                         stribeck_factor=inlined(_mechanics.stribeck_factor), **_substep_parts)


def _no_drop(i, V_lost, inv_i_0):
    return 0.0


def _no_stribeck(omega, omega_s):
    return 0.0


#: :func:`substep` of an ideal plant: an inverter without dead time and friction without a
#: Stribeck drop (the kernels run it where no candidate loses a volt or has a Stribeck
#: speed): the same numbers, none of the work
substep_ideal_inline = inlined(substep, dead_time_drop=inline(_no_drop),
                               stribeck_factor=inline(_no_stribeck), **_substep_parts)
