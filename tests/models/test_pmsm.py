"""The electrical drive: PMSM back-EMF and torque (Eq. 2, 5, 6), Clarke/Park, modulation,
and the exact-exponential phase step checked against an independent ODE solution."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from emaphm.faults import apply_faults, scenario
from emaphm.models.inverter import (clarke, inv_clarke, inv_park, modulate, on_fraction, park,
                                    triangle)
from emaphm.models.pmsm import back_emf_coeffs, phase_step, rl_coeffs, torque
from emaphm.params import siemens_1fk7060

PHI = np.array([0.0, 2 * math.pi / 3, 4 * math.pi / 3])     # phase displacement, a b c
P_POLES = 4
C0 = siemens_1fk7060().motor.c0[0]

angle = st.floats(-50.0, 50.0, allow_nan=False)
amp = st.floats(0.0, 20.0, allow_nan=False)
pos = st.floats(0.1, 3.0, allow_nan=False)
unit = st.floats(0.0, 1.0, allow_nan=False)


def coeffs(theta_m, c0=(C0, C0, C0), ecc=0.0, ecc_phase=0.0, p=P_POLES):
    th_e = p * theta_m
    return back_emf_coeffs(theta_m, math.sin(th_e), math.cos(th_e), *c0, ecc, ecc_phase)


def eq2(theta_m, c0, k6, k7, p=P_POLES):
    """Paper Eq. 2, written independently: c_j = c_j0 (1 + k6 cos(theta_m + phase + d_j)),
    d = 0, +2pi/3, -2pi/3, with c_j0 = c0_j sin(p theta_m - (j-1) 2pi/3) and the phase
    2 pi (k7 - 0.5) (Table 1: -180..180 deg)."""
    phase = 2 * math.pi * (k7 - 0.5)
    d = (0.0, 2 * math.pi / 3, -2 * math.pi / 3)
    return tuple(c0[j] * math.sin(p * theta_m - j * 2 * math.pi / 3)
                 * (1 + k6 * math.cos(theta_m + phase + d[j])) for j in range(3))


# --------------------------------------------------------------------------- back-EMF, torque

@given(theta=angle, c0=pos)
def test_back_emf_coefficients_are_phase_shifted_sines(theta, c0):
    c = coeffs(theta, (c0, c0, c0))
    expected = c0 * np.sin(P_POLES * theta - PHI)
    np.testing.assert_allclose(c, expected, rtol=0, atol=1e-12 * c0)
    assert sum(c) == pytest.approx(0.0, abs=1e-12)


@given(omega=st.floats(-300.0, 300.0))
def test_back_emf_amplitude_is_c0_omega(omega):
    th = np.linspace(0.0, 2 * math.pi / P_POLES, 2001)      # one electrical period
    e = np.array([[cj * omega for cj in coeffs(t)] for t in th])
    for j in range(3):
        assert np.max(np.abs(e[:, j])) == pytest.approx(C0 * abs(omega), rel=1e-6, abs=1e-12)
    # line-to-line RMS at 1000 rpm is the data sheet's k_E = 135 V
    w = 1000 * 2 * math.pi / 60
    e_ab = np.array([(coeffs(t)[0] - coeffs(t)[1]) * w for t in th])
    assert np.sqrt(np.mean(e_ab[:-1] ** 2)) == pytest.approx(135.0, rel=1e-6)


@given(theta=angle, current=amp, c0=pos)
def test_balanced_currents_give_torque_1p5_c0_i(theta, current, c0):
    i = current * np.sin(P_POLES * theta - PHI)
    c = coeffs(theta, (c0, c0, c0))
    assert torque(*i, *c) == pytest.approx(1.5 * c0 * current, rel=1e-12, abs=1e-12)
    assert torque.py_func(*i, *c) == torque(*i, *c)
    # a d-axis current (90 degrees ahead) makes no torque
    i_d = current * np.cos(P_POLES * theta - PHI)
    assert torque(*i_d, *c) == pytest.approx(0.0, abs=1e-12 * max(1.0, current * c0))


@given(theta=angle, c0a=pos, c0b=pos, c0c=pos, k6=unit, k7=unit)
def test_eccentricity_follows_eq2_exactly(theta, c0a, c0b, c0c, k6, k7):
    c0 = (c0a, c0b, c0c)
    got = coeffs(theta, c0, ecc=k6, ecc_phase=2 * math.pi * (k7 - 0.5))
    np.testing.assert_allclose(got, eq2(theta, c0, k6, k7), rtol=1e-12, atol=1e-12)
    # the Python and compiled versions agree
    th_e = P_POLES * theta
    py = back_emf_coeffs.py_func(theta, math.sin(th_e), math.cos(th_e), *c0, k6, 2 * math.pi * (k7 - 0.5))
    np.testing.assert_allclose(py, got, rtol=1e-15, atol=1e-15)


@given(theta=angle, k6=unit)
def test_k7_half_means_phase_zero(theta, k6):
    m = apply_faults(siemens_1fk7060(), [0, 0, 0, 0, 0, k6, 0.5, 0.5]).motor
    assert m.ecc_phase == 0.0
    got = coeffs(theta, m.c0, ecc=m.ecc, ecc_phase=m.ecc_phase)
    base = np.sin(P_POLES * theta - PHI) * C0
    mod = 1 + k6 * np.cos(theta + np.array([0.0, 2 * math.pi / 3, -2 * math.pi / 3]))
    np.testing.assert_allclose(got, base * mod, rtol=1e-12, atol=1e-12)


def test_eccentricity_known_values():
    # at theta_m = 0 phase a's modulation is 1 + k6 cos(phase): with k6 = 0.5, k7 = 0.5 -> 1.5,
    # k7 = 0 or 1 -> 0.5; sample where sin(p theta_m) = 1 on phase a
    theta = math.pi / (2 * P_POLES)
    for k7, factor in [(0.5, 1 + 0.5 * math.cos(theta)), (0.0, 1 - 0.5 * math.cos(theta)),
                       (0.75, 1 - 0.5 * math.sin(theta))]:
        ca = coeffs(theta, ecc=0.5, ecc_phase=2 * math.pi * (k7 - 0.5))[0]
        assert ca == pytest.approx(C0 * factor, rel=1e-12)
    # zero modulus: no effect whatever the phase
    for ph in (-3.0, 0.0, 2.0):
        assert coeffs(1.234, ecc=0.0, ecc_phase=ph) == coeffs(1.234)


# --------------------------------------------------------------------------- transforms

three = st.tuples(st.floats(-100, 100), st.floats(-100, 100), st.floats(-100, 100))


@given(x=three)
def test_clarke_round_trip_without_zero_sequence(x):
    x = np.array(x) - np.mean(x)
    back = inv_clarke(*clarke(*x))
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-12)


@given(ab=st.tuples(st.floats(-100, 100), st.floats(-100, 100)), th=angle)
def test_park_round_trip(ab, th):
    s, c = math.sin(th), math.cos(th)
    back = inv_park(*park(*ab, s, c), s, c)
    np.testing.assert_allclose(back, ab, rtol=0, atol=1e-12)
    fwd = park(*inv_park(*ab, s, c), s, c)
    np.testing.assert_allclose(fwd, ab, rtol=0, atol=1e-12)


@given(theta=angle, current=amp, i_d=st.floats(-10, 10))
def test_balanced_currents_are_a_q_axis_current(theta, current, i_d):
    th_e = P_POLES * theta
    i = current * np.sin(th_e - PHI) + i_d * np.cos(th_e - PHI)
    got_d, got_q = park(*clarke(*i), math.sin(th_e), math.cos(th_e))
    assert got_q == pytest.approx(current, abs=1e-11)
    assert got_d == pytest.approx(i_d, abs=1e-11)
    # and back: dq -> abc gives the phase currents
    back = inv_clarke(*inv_park(got_d, got_q, math.sin(th_e), math.cos(th_e)))
    np.testing.assert_allclose(back, i, rtol=0, atol=1e-10)


@given(theta=angle, amp_v=st.floats(0.0, 1.0), V_dc=st.floats(100.0, 800.0))
def test_modulation_keeps_line_voltages_in_the_linear_range(theta, amp_v, V_dc):
    v = amp_v * V_dc / math.sqrt(3) * np.sin(theta - PHI)     # up to the linear limit
    d = np.array(modulate(*v, V_dc))
    assert np.all(d >= 0.0) and np.all(d <= 1.0)
    line = (d - np.roll(d, -1)) * V_dc
    np.testing.assert_allclose(line, v - np.roll(v, -1), rtol=0, atol=1e-9 * V_dc)


def test_modulation_clips_beyond_the_linear_range():
    V_dc = 600.0
    d = modulate(*(1.5 * V_dc / math.sqrt(3) * np.sin(0.3 - PHI)), V_dc)
    assert min(d) == 0.0 or max(d) == 1.0
    assert all(0.0 <= x <= 1.0 for x in d)


@given(d=unit, half=st.integers(1, 64))
def test_pwm_sub_steps_apply_the_exact_volt_seconds(d, half):
    """Over one carrier period the on-fractions of the n_sub sub-steps average to the duty."""
    n = 2 * half
    frac = [on_fraction(d, triangle(s / n), triangle((s + 1) / n)) for s in range(n)]
    assert all(0.0 <= f <= 1.0 for f in frac)
    assert sum(frac) / n == pytest.approx(d, abs=1e-12)
    assert triangle(0.0) == 0.0 and triangle(0.5) == 1.0 and triangle(1.0) == 0.0


# --------------------------------------------------------------------------- RL step

@given(R=st.floats(1e-3, 10.0), L=st.floats(1e-7, 0.1), dt=st.floats(1e-8, 1e-3))
def test_rl_coeffs_are_the_exact_exponential(R, L, dt):
    a, h = rl_coeffs(R, L, dt)
    assert a == pytest.approx(math.exp(-dt * R / L), rel=1e-14, abs=1e-300)
    x = dt * R / L
    assert h == pytest.approx(-math.expm1(-x) / R, rel=1e-14)
    assert h * R + a == pytest.approx(1.0, rel=1e-14)
    if x < 1e-4:                                                    # series: dt/L (1 - x/2)
        assert h == pytest.approx(dt / L * (1 - x / 2), rel=1e-8)
    assert 0.0 <= a < 1.0 and 0.0 < h <= dt / L * (1 + 1e-12)     # stable, at most the Euler gain


@given(i=st.tuples(st.floats(-20, 20), st.floats(-20, 20)), v=three, e=three,
       R=st.tuples(pos, pos, pos), L=st.tuples(*[st.floats(1e-6, 0.05)] * 3), dt=st.floats(1e-7, 1e-3))
def test_phase_step_keeps_the_star_constraint(i, v, e, R, L, dt):
    ia, ib = i
    ic = -ia - ib
    ab = [rl_coeffs(R[j], L[j], dt) for j in range(3)]
    a = [x[0] for x in ab]
    h = [x[1] for x in ab]
    ja, jb, jc, vn = phase_step(ia, ib, ic, *v, *e, *a, *h)
    assert ja + jb + jc == pytest.approx(0.0, abs=1e-9 * (1 + abs(ja) + abs(jb) + abs(jc)))
    # a common voltage on all legs only moves the star point
    ka, kb, kc, vn2 = phase_step(ia, ib, ic, *(np.array(v) + 123.0), *e, *a, *h)
    np.testing.assert_allclose((ka, kb, kc), (ja, jb, jc), rtol=1e-9, atol=1e-9)
    assert vn2 == pytest.approx(vn + 123.0, rel=1e-9, abs=1e-6)


def test_phase_step_reaches_the_dc_steady_state():
    R = (3.15, 1.0, 2.0)
    L = (22e-3, 5e-3, 1e-2)
    v = (300.0, 280.0, 290.0)
    dt = 1e-4
    ab = [rl_coeffs(R[j], L[j], dt) for j in range(3)]
    i = (0.0, 0.0, 0.0)
    for _ in range(5000):
        *i, vn = phase_step(*i, *v, 0.0, 0.0, 0.0, *[x[0] for x in ab], *[x[1] for x in ab])
    # DC: i_j = (v_j - v_n)/R_j with sum i = 0
    vn_dc = sum(vj / rj for vj, rj in zip(v, R)) / sum(1 / rj for rj in R)
    np.testing.assert_allclose(i, [(vj - vn_dc) / rj for vj, rj in zip(v, R)], rtol=1e-10)
    assert vn == pytest.approx(vn_dc, rel=1e-12)


# --------------------------------------------------------------------------- independent ODE

T_S = 125e-6          # a PWM period; leg voltages are held over it
N_PERIODS = 80        # 10 ms, more than one electrical time constant
OMEGA = 60.0          # rad/s, prescribed constant rotation
THETA0 = 0.3
I0 = (1.0, -0.4, -0.6)

BALANCED = dict(R=(3.15,) * 3, L=(22e-3,) * 3, c0=(C0,) * 3)
_sc = apply_faults(siemens_1fk7060(), scenario("short-circuit-high")).motor   # phase A 75 % shorted
SHORTED = dict(R=_sc.R, L=_sc.L, c0=_sc.c0)


def _leg_voltages(omega):
    """Piecewise-constant leg voltages (against the negative rail), one row per period:
    a sine set at the electrical frequency around V_dc/2, with a dither so that the
    voltage steps are irregular."""
    k = np.arange(N_PERIODS)
    th_e = P_POLES * (THETA0 + omega * k * T_S)
    dither = 5.0 * np.sin(1.7 * k)[:, None] * np.array([1.0, -0.5, 0.3])
    return 300.0 + 75.0 * np.sin(th_e[:, None] + 0.4 - PHI) + dither


def _emf(t, c0, omega):
    return np.asarray(c0) * np.sin(P_POLES * (THETA0 + omega * t) - PHI) * omega


def _solve_ivp(R, L, c0, omega, V):
    """Eq. 5 with the star point solved from sum i = 0, by Radau at tight tolerances,
    restarted at every voltage step. Returns the currents at the period ends (n+1, 3)."""
    R, L = np.asarray(R), np.asarray(L)

    def rhs(t, i, v):
        u = v - _emf(t, c0, omega) - R * i             # = L di/dt + v_n
        v_n = np.sum(u / L) / np.sum(1.0 / L)          # sum di/dt = 0
        return (u - v_n) / L

    i = np.array(I0, dtype=float)
    out = [i.copy()]
    for k in range(V.shape[0]):
        sol = solve_ivp(rhs, (k * T_S, (k + 1) * T_S), i, method="Radau", rtol=1e-11, atol=1e-12,
                        args=(V[k],))
        assert sol.success
        i = sol.y[:, -1]
        out.append(i.copy())
    return np.array(out)


def _phase_steps(R, L, c0, omega, V, n_sub):
    """The models' update: phase_step with the back-EMF at the start of each step."""
    dt = T_S / n_sub
    ab = [rl_coeffs(R[j], L[j], dt) for j in range(3)]
    a = [x[0] for x in ab]
    h = [x[1] for x in ab]
    i = I0
    out = [i]
    for k in range(V.shape[0]):
        for s in range(n_sub):
            th = THETA0 + omega * (k * T_S + s * dt)
            c = coeffs(th, c0)
            *i, _ = phase_step(*i, *V[k], *(cj * omega for cj in c), *a, *h)
        out.append(tuple(i))
    return np.array(out)


@pytest.fixture(scope="module", params=["balanced", "shorted"])
def circuit(request):
    case = BALANCED if request.param == "balanced" else SHORTED
    V = _leg_voltages(OMEGA)
    return request.param, case, V, _solve_ivp(**case, omega=OMEGA, V=V)


def test_independent_solution_is_sane(circuit):
    _, case, _, ref = circuit
    assert np.abs(ref.sum(axis=1)).max() < 1e-9
    assert 1.0 < np.abs(ref).max() < 30.0


def test_phase_step_matches_the_ode_at_a_small_step(circuit):
    name, case, V, ref = circuit
    got = _phase_steps(**case, omega=OMEGA, V=V, n_sub=256)        # dt = 0.49 us
    err = np.abs(got - ref).max()
    # measured 6.7e-4 A (balanced, peak 5.3 A) and 7.7e-4 A (shorted, peak 11.2 A)
    assert err < 2e-3, (name, err)
    assert err / np.abs(ref).max() < 3e-4


def test_phase_step_error_falls_at_first_order(circuit):
    name, case, V, ref = circuit
    n_subs = np.array([1, 2, 4, 8, 16, 32])
    errs = np.array([np.abs(_phase_steps(**case, omega=OMEGA, V=V, n_sub=n) - ref).max()
                     for n in n_subs])
    order = np.polyfit(np.log(T_S / n_subs), np.log(errs), 1)[0]
    # measured 1.00 for both: the back-EMF (and star point) is held over the step
    assert 0.9 < order < 1.2, (name, order, errs)
    assert np.all(np.diff(errs) < 0)


def test_phase_step_is_exact_for_a_balanced_motor_at_standstill():
    """With omega = 0 and equal phases the star point is constant over a step, so the
    exponential update is the exact solution whatever the step."""
    V = _leg_voltages(0.0)
    ref = _solve_ivp(**BALANCED, omega=0.0, V=V)
    for n_sub in (1, 4):
        got = _phase_steps(**BALANCED, omega=0.0, V=V, n_sub=n_sub)
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-8)


def test_phase_step_at_standstill_with_a_shorted_phase_converges():
    """Unequal time constants make the star point vary inside a step: not exact, but close
    and convergent (measured 4.1e-4, 2.5e-5, 1.6e-6 A at n_sub = 1, 4, 16)."""
    V = _leg_voltages(0.0)
    ref = _solve_ivp(**SHORTED, omega=0.0, V=V)
    errs = [np.abs(_phase_steps(**SHORTED, omega=0.0, V=V, n_sub=n) - ref).max() for n in (1, 4, 16)]
    assert errs[0] < 2e-3
    assert errs[1] < errs[0] / 4 and errs[2] < errs[1] / 4
