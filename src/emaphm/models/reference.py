"""Reference model (RM): the high-fidelity "numerical test bench".

The same drive as the monitoring model (cascade controller and dq current
loop sampled once per PWM period ``T_s``), but the inverter **switches**: each
leg is on while a symmetric triangular carrier is below its duty cycle. Every
control period is cut into ``n_sub`` (even, default 128, about 1 us at 8 kHz)
sub-steps; each sub-step applies the exact volt-seconds of the switched leg
voltage (:func:`emaphm.models.inverter.on_fraction`), so the current ripple is
resolved and no duty is lost to the step. Currents are sampled at the carrier
valley, where a real drive samples them (the ripple's mean).

Optional sensor effects (:class:`Sensors`) act on the recorded signals, as the
acquisition chain of the PHM recorder: Gaussian current noise from an explicit
seed, current quantisation, encoder quantisation. The drive's own loop sees
the clean signals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..faults import apply_faults, as_k
from ..params import ActuatorParams
from ..profiles import Profile
from ._jit import jit
from .controller import control_step
from .inverter import modulate, on_fraction, overcurrent, triangle
from .layout import (C_BACKLASH, C_C0_A, C_C0_B, C_C0_C, C_ECC, C_ECC_PHASE, C_FDJ, C_FSJ, C_KP,
                     C_L_A, C_R_A, P_C_L, P_C_M, P_I_MAX, P_J_L, P_J_M, P_K_T, P_KD, P_KI, P_KI_I,
                     P_KI_W, P_KP_I, P_KP_W, P_OMEGA_MAX, P_POLES, P_I_TRIP, P_T_MAX, P_T_S, P_THETA0, P_V_DC,
                     pack)
from .mechanics import transmission_step
from .pmsm import back_emf_coeffs, phase_step, rl_coeffs, torque

__all__ = ["Sensors", "run_reference"]


@dataclass(frozen=True)
class Sensors:
    """Acquisition chain of the recorded signals.

    ``current_noise`` [A rms] white Gaussian noise on each phase current;
    ``current_lsb`` [A] quantisation step of the current ADC (0 = ideal);
    ``encoder_counts`` [counts/rev] position quantisation (0 = ideal).
    """

    current_noise: float = 0.0
    current_lsb: float = 0.0
    encoder_counts: int = 0

    def __post_init__(self) -> None:
        for name in ("current_noise", "current_lsb"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"Sensors.{name} [A] must be >= 0, got {v!r}")
        if isinstance(self.encoder_counts, bool) or not isinstance(self.encoder_counts, int) \
                or self.encoder_counts < 0:
            raise ValueError(f"Sensors.encoder_counts [counts/rev] must be an integer >= 0, "
                             f"got {self.encoder_counts!r}")

    @property
    def ideal(self) -> bool:
        return self.current_noise == 0 and self.current_lsb == 0 and self.encoder_counts == 0

    def apply(self, theta_m: np.ndarray, i_abc: np.ndarray,
              rng: np.random.Generator | None) -> tuple[np.ndarray, np.ndarray]:
        """Measured ``(theta_m, i_abc)`` from the true signals (new arrays)."""
        i = np.array(i_abc, dtype=float, copy=True)
        if self.current_noise > 0:
            if rng is None:
                raise ValueError("sensor noise needs an explicit seed (seed=...)")
            i += rng.normal(0.0, self.current_noise, size=i.shape)
        if self.current_lsb > 0:
            i = np.round(i / self.current_lsb) * self.current_lsb
        th = np.array(theta_m, dtype=float, copy=True)
        if self.encoder_counts > 0:
            q = 2 * np.pi / self.encoder_counts
            th = np.floor(th / q) * q
        return th, i


@jit
def _rm_kernel(P, cp, theta_ref, T_load, n_sub, pwm,
               out_i, out_theta, out_omega, out_torque, out_energy, trip_index):
    """One actuator over ``theta_ref.shape[0]`` control periods at step ``T_s/n_sub``.

    ``out_energy (n, 4)`` receives cumulative [input, copper loss, air-gap
    (T_m * omega_m), stored magnetic] energies in J at each sample;
    ``trip_index[0]`` the sample at which the drive tripped on overcurrent (-1: never).
    """
    n = theta_ref.shape[0]
    p = P[P_POLES]
    T_s = P[P_T_S]
    dt = T_s / n_sub
    V_dc = P[P_V_DC]
    J_m, C_m, J_l, C_l = P[P_J_M], P[P_C_M], P[P_J_L], P[P_C_L]
    a_a, h_a = rl_coeffs(cp[C_R_A], cp[C_L_A], dt)
    a_b, h_b = rl_coeffs(cp[C_R_A + 1], cp[C_L_A + 1], dt)
    a_c, h_c = rl_coeffs(cp[C_R_A + 2], cp[C_L_A + 2], dt)
    R_a, R_b, R_c = cp[C_R_A], cp[C_R_A + 1], cp[C_R_A + 2]
    L_a, L_b, L_c = cp[C_L_A], cp[C_L_A + 1], cp[C_L_A + 2]
    thm = P[P_THETA0]
    wm = 0.0
    thl = P[P_THETA0]
    wl = 0.0
    ia = 0.0
    ib = 0.0
    ic = 0.0
    i0 = 0.0
    i1 = 0.0
    i2 = 0.0
    i3 = 0.0
    E_in = 0.0
    E_cu = 0.0
    E_ag = 0.0
    tripped = False
    trip_index[0] = -1
    for k in range(n):
        s_e = math.sin(p * thm)
        c_e = math.cos(p * thm)
        ca, cb, cc = back_emf_coeffs(thm, s_e, c_e, cp[C_C0_A], cp[C_C0_B], cp[C_C0_C],
                                     cp[C_ECC], cp[C_ECC_PHASE])
        out_i[k, 0] = ia
        out_i[k, 1] = ib
        out_i[k, 2] = ic
        out_theta[k] = thm
        out_omega[k] = wm
        out_torque[k] = torque(ia, ib, ic, ca, cb, cc)
        out_energy[k, 0] = E_in
        out_energy[k, 1] = E_cu
        out_energy[k, 2] = E_ag
        out_energy[k, 3] = 0.5 * (L_a * ia * ia + L_b * ib * ib + L_c * ic * ic)
        if not tripped and overcurrent(ia, ib, ic, P[P_I_TRIP]):
            tripped = True
            trip_index[0] = k
        if tripped:                    # active short circuit, controller stopped
            d_a = d_b = d_c = 0.0
        else:
            v_a, v_b, v_c, T_ref, i0, i1, i2, i3 = control_step(
                theta_ref[k], thm, wm, ia, ib, ic, s_e, c_e, i0, i1, i2, i3,
                cp[C_KP], P[P_KI], P[P_KD], P[P_OMEGA_MAX], P[P_KP_W], P[P_KI_W],
                P[P_T_MAX], P[P_K_T], P[P_I_MAX], P[P_KP_I], P[P_KI_I], V_dc, T_s)
            d_a, d_b, d_c = modulate(v_a, v_b, v_c, V_dc)
        for s in range(n_sub):
            if s > 0:
                s_e = math.sin(p * thm)
                c_e = math.cos(p * thm)
                ca, cb, cc = back_emf_coeffs(thm, s_e, c_e, cp[C_C0_A], cp[C_C0_B], cp[C_C0_C],
                                             cp[C_ECC], cp[C_ECC_PHASE])
            if pwm:
                c0 = triangle(s / n_sub)
                c1 = triangle((s + 1) / n_sub)
                va = V_dc * on_fraction(d_a, c0, c1)
                vb = V_dc * on_fraction(d_b, c0, c1)
                vc = V_dc * on_fraction(d_c, c0, c1)
            else:
                va = V_dc * d_a
                vb = V_dc * d_b
                vc = V_dc * d_c
            ja, jb, jc, _ = phase_step(ia, ib, ic, va, vb, vc, ca * wm, cb * wm, cc * wm,
                                       a_a, a_b, a_c, h_a, h_b, h_c)
            # the mechanics see the step's mean torque (trapezoid, as in the MM)
            T_mean = 0.5 * (torque(ia, ib, ic, ca, cb, cc) + torque(ja, jb, jc, ca, cb, cc))
            E_in += 0.5 * dt * (va * (ia + ja) + vb * (ib + jb) + vc * (ic + jc))
            E_cu += 0.5 * dt * (R_a * (ia * ia + ja * ja) + R_b * (ib * ib + jb * jb)
                                + R_c * (ic * ic + jc * jc))
            ia, ib, ic = ja, jb, jc
            w0 = wm
            thm, wm, thl, wl = transmission_step(thm, wm, thl, wl, T_mean, T_load[k], J_m, C_m,
                                                 cp[C_FSJ], cp[C_FDJ], J_l, C_l, cp[C_BACKLASH], dt)
            E_ag += 0.5 * dt * T_mean * (w0 + wm)


def run_reference(params: ActuatorParams, k, profile: Profile, *, n_sub: int = 128,
                  pwm: bool = True) -> dict[str, np.ndarray]:
    """Simulate the faulty actuator ``apply_faults(params, k)`` with ideal sensors.

    Returns a dict ``t, theta_ref, theta_m, omega_m, i_abc (n, 3), torque,
    energy (n, 4)`` sampled at the control instants ``k*T_s``, and
    ``trip_time`` [s] when the drive tripped on overcurrent (None if never).
    """
    if isinstance(n_sub, bool) or not isinstance(n_sub, int) or n_sub < 2 or n_sub % 2:
        raise ValueError(f"reference model n_sub must be an even integer >= 2 (sub-steps per "
                         f"PWM period, so that none straddles the carrier peak), got {n_sub!r}")
    faulty = apply_faults(params, as_k(k))
    P, CP = pack(faulty)
    t = profile.grid(params.inverter.T_s)
    ref = np.ascontiguousarray(profile.theta_ref(t))
    load = np.ascontiguousarray(profile.load_torque(t))
    n = t.size
    out = {"i_abc": np.zeros((n, 3)), "theta_m": np.zeros(n), "omega_m": np.zeros(n),
           "torque": np.zeros(n), "energy": np.zeros((n, 4))}
    trip = np.full(1, -1, dtype=np.int64)
    _rm_kernel(P, CP[0], ref, load, n_sub, bool(pwm), out["i_abc"], out["theta_m"],
               out["omega_m"], out["torque"], out["energy"], trip)
    out.update(t=t, theta_ref=ref, trip_time=None if trip[0] < 0 else float(t[trip[0]]))
    return out
