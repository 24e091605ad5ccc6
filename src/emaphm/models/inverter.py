"""Clarke-Park transforms, space-vector modulation and the PWM carrier.

Conventions (amplitude invariant, ``theta_e = p * theta_m``), the textbook's dq frame:
the d axis on the magnet's flux, the q axis 90 electrical degrees ahead of it. The
back-EMF of phase a is ``c0 omega_m sin(theta_e)``, so the magnet's flux linkage is
``psi_a = -psi_m cos(theta_e)`` (``psi_m = c0 / p``) and the d axis points at
``theta_e + pi``. A q-axis current ``I`` gives ``i_j = I sin(theta_e - phi_j)``, in
phase with the back-EMF, so ``T_m = 1.5 c0 i_q``; a positive ``i_d`` strengthens the
field, a negative one weakens it. In steady state at ``omega_e = p omega_m``,

    u_d = R i_d - omega_e L i_q          u_q = R i_q + omega_e (L i_d + psi_m)

(``tests/models/test_pmsm.py`` checks the winding model against it).

    i_alpha = 2/3 (i_a - i_b/2 - i_c/2)       i_beta = (i_b - i_c)/sqrt(3)
    i_d = -(i_alpha cos(theta_e) + i_beta sin(theta_e))
    i_q = i_alpha sin(theta_e) - i_beta cos(theta_e)
"""

import math

from ._jit import jit

SQRT3 = math.sqrt(3.0)


@jit
def clarke(x_a, x_b, x_c):
    """abc -> alpha-beta (amplitude invariant)."""
    return (2.0 * x_a - x_b - x_c) / 3.0, (x_b - x_c) / SQRT3


@jit
def inv_clarke(x_alpha, x_beta):
    """alpha-beta -> abc (zero sequence zero)."""
    return (x_alpha,
            -0.5 * x_alpha + 0.5 * SQRT3 * x_beta,
            -0.5 * x_alpha - 0.5 * SQRT3 * x_beta)


@jit
def park(x_alpha, x_beta, sin_e, cos_e):
    """alpha-beta -> dq (d on the magnet's flux) at the electrical angle given by its sine
    and cosine."""
    return -(x_alpha * cos_e + x_beta * sin_e), x_alpha * sin_e - x_beta * cos_e


@jit
def inv_park(x_d, x_q, sin_e, cos_e):
    """dq -> alpha-beta (the inverse of :func:`park`)."""
    return -x_d * cos_e + x_q * sin_e, -x_d * sin_e - x_q * cos_e


@jit
def modulate(v_a, v_b, v_c, V_dc):
    """Phase voltage references -> leg duty cycles in [0, 1].

    Min-max zero-sequence injection (equivalent to space-vector PWM): linear up
    to a phase amplitude of ``V_dc/sqrt(3)``; beyond, the duties clip.
    """
    hi = max(v_a, max(v_b, v_c))
    lo = min(v_a, min(v_b, v_c))
    off = 0.5 * V_dc - 0.5 * (hi + lo)
    return (min(max((v_a + off) / V_dc, 0.0), 1.0),
            min(max((v_b + off) / V_dc, 0.0), 1.0),
            min(max((v_c + off) / V_dc, 0.0), 1.0))


@jit
def triangle(x):
    """Symmetric carrier over one period, ``x`` in [0, 1]: 0 at the ends, 1 at 0.5."""
    return 1.0 - abs(1.0 - 2.0 * x)


@jit
def on_fraction(d, c_start, c_end):
    """Share of a sub-step during which a leg with duty ``d`` is on (carrier < d).

    The carrier runs linearly from ``c_start`` to ``c_end`` over the sub-step
    (which must not straddle a carrier peak). Exact volt-seconds per sub-step.
    """
    if c_end > c_start:
        return min(max((d - c_start) / (c_end - c_start), 0.0), 1.0)
    return 1.0 - min(max((c_start - d) / (c_start - c_end), 0.0), 1.0)


@jit
def overcurrent(i_a, i_b, i_c, I_trip):
    """True when a sampled phase current exceeds the trip level (drive protection)."""
    return abs(i_a) > I_trip or abs(i_b) > I_trip or abs(i_c) > I_trip


#: The current [A] below which the dead time's voltage error fades, as a share of the
#: drive's current limit: the legs' own PWM ripple carries a phase current across zero
#: within a period near its zero crossings, which smooths the sign of the error. Measured
#: on the reference plant (1 us of dead time, 600 V, 8 kHz): the recorded-voltage winding
#: model fits its currents best with 0.2-0.6 % of I_max (20-85 mA on the preset), 3x
#: worse at 1 %.
DEAD_TIME_SHARE = 0.003


def dead_time_width(I_max: float) -> float:
    """``i_0`` [A]: the current below which the dead time's voltage error fades linearly,
    :data:`DEAD_TIME_SHARE` of the drive's current limit ``I_max`` [A]."""
    return DEAD_TIME_SHARE * I_max


@jit
def dead_time_drop(i, V_lost, inv_i_0):
    """The voltage [V] a leg loses to dead time and device drops at the phase current
    ``i`` [A]: ``V_lost`` opposing the current, fading linearly below ``i_0`` (given as
    ``1 / i_0``), an average over the period of the plant's switched sign."""
    return V_lost * min(max(i * inv_i_0, -1.0), 1.0)
