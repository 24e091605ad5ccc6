"""Discrete cascade controller of the drive, run once per control period T_s.

position PID -> speed reference (saturated at omega_max)
(+ velocity feed-forward, saturated again)
speed PI (2-DOF: proportional on ``b omega_ref - omega_f``) -> torque reference
(saturated at T_max; + torque feed-forward, saturated again)
i_q,ref = T_ref / k_T (saturated at I_max; low-pass filtered), i_d,ref = 0
dq current PI with back-EMF feed-forward (and dq decoupling) -> phase voltage
references (the textbook dq frame, d on the magnet's flux: :mod:`emaphm.models.inverter`),
applied at once or one control period later

Every integrator has back-calculation anti-windup (Astrom & Hagglund): while
the output saturates, the integral is pulled towards the saturated value with
the tracking time constant ``T_t = Kp/Ki`` (the integral time). Unlike a
clamp that switches integration on and off, this is continuous in the gains,
so the fitness landscape has no step where a transient just touches a limit.
The controller
knows the healthy motor only (``k_T``, its ``c0 = k_T/1.5``); faults change
the plant, never the controller's model of it, except k8, which drifts ``Kp``.

The drive's settings are one tuple (:data:`CTL_FIELDS`, in that order; the model's
layout packs them from :class:`emaphm.params.Controller` and :class:`emaphm.params.Inverter`),
its state another (:data:`STATE_FIELDS`); :func:`control_step` takes and returns them
whole, so that a setting or a state added to the drive changes this module and the
layout's packing, and no caller. Where each option acts:

* ``K_vff`` (velocity feed-forward): ``K_vff (ref_k - ref_{k-1}) / T_s`` added to the
  speed reference after the position PID's saturation, the sum saturated again at
  ``omega_max``;
* ``J_tff`` (torque feed-forward gain times its inertia, ``torque_feedforward *
  torque_feedforward_inertia``): ``J_tff (ref_k - 2 ref_{k-1} + ref_{k-2}) / T_s^2``
  added to the speed PI's output outside its anti-windup, the sum saturated at ``T_max``;
* ``a_w`` (speed filter, ``1 - exp(-T_s / tau)``; 1 without one): the filtered speed
  ``omega_f`` feeds the speed PI and the position loop's derivative; the back-EMF
  feed-forward and the decoupling keep the raw speed;
* ``b_w``: the speed PI's reference weight (its proportional part acts on
  ``b_w omega_ref - omega_f``, its integral on ``omega_ref - omega_f``);
* ``a_i`` (current-reference filter, ``1 - exp(-T_s / tau)``; 1 without one) on i_q,ref;
* ``decoupling`` (0 or 1): ``-omega_e L_d i_q`` on v_d and ``+omega_e L_d i_d`` on v_q,
  from the measured currents and speed and the drive's own ``L_d``;
* ``emf_ff`` (0 or 1, default 1): the back-EMF feed-forward ``k_T/1.5 omega_m`` on v_q;
* ``delay`` (0 or 1): the voltage computed from the samples of period k is applied in
  period k + 1 (a computation delay); the voltages of the period before are applied now.

The current limit ``I_max`` is on the q-axis reference (``i_d,ref`` is 0, so it is the
reference's magnitude too). Before the first sample the reference's history is its first
value (the caller passes ``ref_{k-1} = ref_{k-2} = ref_0`` to :func:`feedforward` at
``k = 0``).
"""

import math

from ._jit import jit
from .inverter import clarke, inv_clarke, inv_park, park

#: The drive's settings, in the order of the tuple :func:`control_step` takes.
CTL_FIELDS = ("Ki", "Kd", "omega_max", "Kp_w", "Ki_w", "T_max", "k_T", "I_max", "Kp_i",
              "Ki_i", "V_dc", "T_s", "K_vff", "J_tff", "a_w", "b_w", "a_i", "decoupling",
              "L_d", "emf_ff", "delay", "p")
(CTL_KI, CTL_KD, CTL_OMEGA_MAX, CTL_KP_W, CTL_KI_W, CTL_T_MAX, CTL_K_T, CTL_I_MAX, CTL_KP_I,
 CTL_KI_I, CTL_V_DC, CTL_T_S, CTL_K_VFF, CTL_J_TFF, CTL_A_W, CTL_B_W, CTL_A_I, CTL_DECOUPLING,
 CTL_L_D, CTL_EMF_FF, CTL_DELAY, CTL_P) = range(len(CTL_FIELDS))
N_CTL = len(CTL_FIELDS)

#: The drive's state, in the order of the tuple :func:`control_step` takes and returns:
#: the integrals of the position, speed, d and q current controllers (in output units),
#: the filtered speed [rad/s], the filtered q-current reference [A] and the phase voltage
#: references [V] computed in the period before (applied now under a delay).
STATE_FIELDS = ("int_e", "int_w", "int_d", "int_q", "omega_f", "i_q_f", "v_a1", "v_b1", "v_c1")
N_STATE = len(STATE_FIELDS)


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
def pi2_step(error_p, error, integral, Kp, Ki, limit, T_s):
    """:func:`pi_step` with two degrees of freedom: the proportional part on ``error_p``
    (the reference weighted), the integral and its back-calculation on ``error``."""
    u = Kp * error_p + integral
    y = _sat(u, limit)
    return y, integral + T_s * Ki * (error + (y - u) / Kp)


@jit
def _lowpass(y, x, a):
    """One step of a first-order low-pass ``y + a (x - y)``; ``x`` itself where ``a >= 1``
    (no filter: exactly the input)."""
    return x if a >= 1.0 else y + a * (x - y)


@jit
def _weighted(b, x):
    """The 2-DOF speed PI's weighted reference ``b x``."""
    return b * x


@jit
def _dq_feedforward(v_d, v_q, i_d, i_q, omega_m, ctl):
    """The dq voltages with the decoupling terms (``-omega_e L i_q`` on d, ``+omega_e L
    i_d`` on q, where the drive decouples) and the back-EMF feed-forward
    (``k_T/1.5 omega_m`` on q, where the drive feeds it forward)."""
    w_e_L = ctl[CTL_DECOUPLING] * ctl[CTL_P] * omega_m * ctl[CTL_L_D]
    return (v_d - w_e_L * i_q,
            v_q + w_e_L * i_d + ctl[CTL_EMF_FF] * ((ctl[CTL_K_T] / 1.5) * omega_m))


@jit
def _applied(v_new, v_old, delay):
    """The voltage applied in this period: the one computed now, or under a computation
    delay the one computed in the period before."""
    return v_old if delay != 0.0 else v_new


# The plain cascade (every option at its default: no filters, 2-DOF weight 1, back-EMF
# feed-forward, no decoupling, no delay) computes the same numbers with the option
# helpers above reduced to what they do at their defaults; :func:`plain` tells when, and
# the model's kernels then run :func:`control_step` with these (``emaphm.models.step``), so
# that a drive without options pays nothing for them.

def _lowpass_off(y, x, a):
    return x


def _weighted_off(b, x):
    return x


def _dq_feedforward_off(v_d, v_q, i_d, i_q, omega_m, ctl):
    return v_d, v_q + (ctl[CTL_K_T] / 1.5) * omega_m


def _applied_off(v_new, v_old, delay):
    return v_new


#: The option helpers of :func:`control_step` and their reductions for a plain cascade.
PLAIN = {"_lowpass": _lowpass_off, "_weighted": _weighted_off,
         "_dq_feedforward": _dq_feedforward_off, "_applied": _applied_off}


@jit
def plain(ctl):
    """Whether the drive's options are all at their defaults (:data:`PLAIN` then computes
    :func:`control_step`'s numbers)."""
    return (ctl[CTL_A_W] >= 1.0 and ctl[CTL_A_I] >= 1.0 and ctl[CTL_B_W] == 1.0
            and ctl[CTL_DECOUPLING] == 0.0 and ctl[CTL_EMF_FF] == 1.0 and ctl[CTL_DELAY] == 0.0)


@jit
def feedforward(ref, ref1, ref2, ctl):
    """``(ref, omega_ff, T_ff)``: the position command [rad] of the period and its velocity
    [rad/s] and torque [N m] feed-forward terms from the commands ``ref_k, ref_{k-1},
    ref_{k-2}`` (the same for every candidate of a population: the kernels compute them
    once per period)."""
    T_s = ctl[CTL_T_S]
    return (ref, ctl[CTL_K_VFF] * ((ref - ref1) / T_s),
            ctl[CTL_J_TFF] * ((ref - 2.0 * ref1 + ref2) / (T_s * T_s)))


@jit
def speed_loop(w_ref, w_f, T_ff, int_w, iq_f, ctl):
    """The speed PI (2-DOF) on the (filtered) speed ``w_f`` [rad/s] towards ``w_ref``, the
    torque feed-forward ``T_ff`` [N m] added outside its anti-windup, the torque limit, the
    q-current reference (at ``I_max``, then its filter). Returns ``(T_ref, i_q_ref, int_w)``:
    the torque reference [N m], the filtered q-current reference [A] (the state ``i_q_f``
    too) and the speed integral."""
    T_max = ctl[CTL_T_MAX]
    T_ref, int_w = pi2_step(_weighted(ctl[CTL_B_W], w_ref) - w_f, w_ref - w_f, int_w, ctl[CTL_KP_W],
                            ctl[CTL_KI_W], T_max, ctl[CTL_T_S])
    T_ref = _sat(T_ref + T_ff, T_max)
    iq_f = _lowpass(iq_f, _sat(T_ref / ctl[CTL_K_T], ctl[CTL_I_MAX]), ctl[CTL_A_I])
    return T_ref, iq_f, int_w


@jit
def current_loop(i_d_ref, i_q_ref, i_a, i_b, i_c, omega_m, sin_e, cos_e, int_d, int_q, ctl):
    """The dq current PI at the electrical angle (``sin_e, cos_e``) towards ``(i_d_ref,
    i_q_ref)`` [A] from the phase currents, with the decoupling and the back-EMF
    feed-forward on the speed ``omega_m`` [rad/s], the voltage vector kept in the linear
    modulation range. Returns ``(v_a, v_b, v_c, int_d, int_q)``: the phase voltage references
    computed now [V] (applied now or, under a delay, in the next period) and the integrals.
    The drive's current loop, once: the cascade's (:func:`control_step`) and, where a trace
    records the current references, the monitoring model's (:mod:`emaphm.models.driven`)."""
    i_al, i_be = clarke(i_a, i_b, i_c)
    i_d, i_q = park(i_al, i_be, sin_e, cos_e)
    T_s = ctl[CTL_T_S]
    v_lim = ctl[CTL_V_DC] / math.sqrt(3.0)
    v_d, int_d = pi_step(i_d_ref - i_d, int_d, ctl[CTL_KP_I], ctl[CTL_KI_I], v_lim, T_s)
    v_q, int_q = pi_step(i_q_ref - i_q, int_q, ctl[CTL_KP_I], ctl[CTL_KI_I], v_lim, T_s)
    v_d, v_q = _dq_feedforward(v_d, v_q, i_d, i_q, omega_m, ctl)
    # keep the voltage vector inside the linear modulation range
    mag = math.sqrt(v_d * v_d + v_q * v_q)
    if mag > v_lim:
        v_d *= v_lim / mag
        v_q *= v_lim / mag
    v_al, v_be = inv_park(v_d, v_q, sin_e, cos_e)
    v_a, v_b, v_c = inv_clarke(v_al, v_be)
    return v_a, v_b, v_c, int_d, int_q


@jit
def control_step(refs, theta_m, omega_m, i_a, i_b, i_c, sin_e, cos_e, state, Kp, ctl):
    """One control period from sampled measurements.

    ``refs = (ref_k, omega_ff, T_ff)``: the position command [rad] and the feed-forward
    terms (:func:`feedforward`); ``sin_e, cos_e``:
    sine and cosine of the electrical angle ``p*theta_m``; ``state`` (:data:`STATE_FIELDS`),
    ``Kp`` the position gain [1/s] (k8 drifts it), ``ctl`` the settings
    (:data:`CTL_FIELDS`). Returns ``(v_a, v_b, v_c, refs, state)``: the phase voltage
    references applied in this period [V], the references ``(omega_ref, T_ref, i_q_ref)``
    [rad/s, N m, A] (the speed reference into the speed PI, the torque reference, the
    q-current reference into the current loop: what a drive logs) and the new state.
    The speed loop (:func:`speed_loop`) and the current loop (:func:`current_loop`) are
    their own functions, which the identification from a drive's recorded references runs.
    """
    int_e, int_w, int_d, int_q, w_f, iq_f, va1, vb1, vc1 = state
    ref, w_ff, T_ff = refs
    omega_max = ctl[CTL_OMEGA_MAX]
    w_f = _lowpass(w_f, omega_m, ctl[CTL_A_W])
    # position PID (derivative on the measurement) -> speed reference, + velocity feed-forward
    e = ref - theta_m
    w_ref, int_e = pi_step(e, int_e, Kp, ctl[CTL_KI], omega_max, ctl[CTL_T_S])
    w_ref = _sat(w_ref - ctl[CTL_KD] * w_f + w_ff, omega_max)
    # speed PI (2-DOF) -> torque reference, + torque feed-forward outside the anti-windup
    T_ref, iq_f, int_w = speed_loop(w_ref, w_f, T_ff, int_w, iq_f, ctl)
    # dq current PI at the electrical angle
    v_a, v_b, v_c, int_d, int_q = current_loop(0.0, iq_f, i_a, i_b, i_c, omega_m, sin_e, cos_e,
                                               int_d, int_q, ctl)
    delay = ctl[CTL_DELAY]
    return (_applied(v_a, va1, delay), _applied(v_b, vb1, delay), _applied(v_c, vc1, delay),
            (w_ref, T_ref, iq_f), (int_e, int_w, int_d, int_q, w_f, iq_f, v_a, v_b, v_c))


@jit
def speed_loop_references(omega_ref, omega_m, theta_ref, ctl, out):
    """The drive's q-current references from its recorded speed reference: the speed loop
    (:func:`speed_loop`, from rest: its integral, filters and the reference's history as
    :func:`control_step` starts them) on the measured speed ``omega_m`` (filtered as the
    drive filters it), the torque feed-forward from the position command ``theta_ref``,
    sample by sample. Writes ``out (n,)`` [A]."""
    int_w = 0.0
    w_f = 0.0
    iq_f = 0.0
    n = omega_ref.shape[0]
    for k in range(n):
        w_f = _lowpass(w_f, omega_m[k], ctl[CTL_A_W])
        _, _, T_ff = feedforward(theta_ref[k], theta_ref[max(k - 1, 0)],
                                 theta_ref[max(k - 2, 0)], ctl)
        _, iq_f, int_w = speed_loop(omega_ref[k], w_f, T_ff, int_w, iq_f, ctl)
        out[k] = iq_f
