"""Transmission: Borello's stick/slip dry friction and the backlash dead band (paper Eq. 7),
closed by a rigid contact (``K_c = 0``) or a compliant one (the gear train's stiffness)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from emaphm.models.mechanics import friction_step, transmission_step

J_M = 7.7e-4
J_L = 7.7e-4
FSJ = 0.12
FDJ = 0.08
DT = 125e-6

torque = st.floats(-20.0, 20.0, allow_nan=False)
speed = st.floats(-200.0, 200.0, allow_nan=False).filter(lambda w: w != 0.0)
step = st.floats(1e-7, 1e-3)
inertia = st.floats(1e-5, 1e-2)
levels = st.tuples(st.floats(0.0, 2.0), st.floats(0.0, 1.0)).map(lambda x: (x[0], x[0] * x[1]))


def _run(n, state, T_m, T_l=0.0, *, J_m=J_M, C_m=0.0, FSJ=FSJ, FDJ=FDJ, J_l=J_L, C_l=0.0,
         backlash=2e-4, K_c=0.0, D_c=0.0, dt=DT, fn=transmission_step):
    """n steps of transmission_step from state (th_m, w_m, th_l, w_l); returns all states.
    Rigid contact unless ``K_c > 0``."""
    out = [state]
    for _ in range(n):
        state = fn(*state, T_m, T_l, J_m, C_m, FSJ, FDJ, J_l, C_l, backlash, K_c, D_c, dt)
        out.append(state)
    return np.array(out)


# --------------------------------------------------------------------------- dry friction

@given(T=st.floats(0.0, 1.0), FS=st.floats(0.0, 2.0), J=inertia, dt=step)
def test_body_at_rest_under_static_limit_stays_exactly_still(T, FS, J, dt):
    for sign in (1.0, -1.0):
        Tact = sign * T * FS                          # |T_act| <= FSJ, the limit included
        assert friction_step(0.0, Tact, FS, 0.5 * FS, J, dt) == 0.0


@given(excess=st.floats(1e-6, 10.0), FS=st.floats(0.0, 2.0), J=inertia, dt=step)
def test_breakaway_above_static_limit(excess, FS, J, dt):
    for sign in (1.0, -1.0):
        Tact = sign * (FS + excess)
        w = friction_step(0.0, Tact, FS, 0.5 * FS, J, dt)
        assert w * sign > 0.0                         # moves in the torque's direction
        assert w == pytest.approx(dt * sign * excess / J, rel=1e-9)   # net of the static level


@given(w0=speed, T=torque, lv=levels, J=inertia, dt=step)
def test_speed_never_reverses_within_a_step(w0, T, lv, J, dt):
    FS, FD = lv
    w = friction_step(w0, T, FS, FD, J, dt)
    assert w * math.copysign(1.0, w0) >= 0.0
    free = w0 + dt * (T - FD * math.copysign(1.0, w0)) / J
    if free * math.copysign(1.0, w0) > 0.0:           # keeps moving: explicit Euler with FDJ
        assert w == pytest.approx(free, rel=1e-12, abs=1e-300)
    else:                                             # would cross zero: stops exactly
        assert w == 0.0


def test_opposing_torque_stops_at_zero_instead_of_crossing():
    # 1 rad/s against 5 N m: Euler would give 1 - 125e-6*5.08/7.7e-4 = 0.175, then negative
    w = 1.0
    ws = []
    for _ in range(5):
        w = friction_step(w, -5.0, FSJ, FDJ, J_M, DT)
        ws.append(w)
    assert ws[0] == pytest.approx(1.0 - DT * 5.08 / J_M)
    assert ws[1] == 0.0
    # now at rest under 5 N m > FSJ: breaks away the other way, net of the static level
    assert ws[2] == pytest.approx(-DT * (5.0 - FSJ) / J_M)


@given(w0=st.floats(1.0, 100.0), J=inertia)
def test_moving_body_decelerates_at_dynamic_level(w0, J):
    dt = 1e-3 * J * w0 / FDJ / 50.0                   # 50 000 steps would stop it: take 20
    w = w0
    for n in range(1, 21):
        w = friction_step(w, 0.0, FSJ, FDJ, J, dt)
        assert w == pytest.approx(w0 - n * dt * FDJ / J, rel=1e-9)
    # and negative speeds the same way
    assert friction_step(-w0, 0.0, FSJ, FDJ, J, dt) == pytest.approx(-w0 + dt * FDJ / J)


def test_coasting_body_stops_in_the_predicted_time_and_stays():
    w0 = 10.0
    t_stop = w0 * J_M / FDJ                           # 0.09625 s
    n_stop = math.ceil(t_stop / DT)
    w, stopped_at = w0, None
    for n in range(1, n_stop + 200):
        w = friction_step(w, 0.0, FSJ, FDJ, J_M, DT)
        if w == 0.0 and stopped_at is None:
            stopped_at = n
        if stopped_at is not None:
            assert w == 0.0
    assert stopped_at in (n_stop - 1, n_stop)


# --------------------------------------------------------------------------- transmission_step

@pytest.mark.parametrize("backlash", [0.0, 2e-4, 2e-2])
@pytest.mark.parametrize("frac", [0.0, 0.5, 0.999, 1.0])
def test_torque_below_breakaway_never_moves(backlash, frac):
    for sign in (1.0, -1.0):
        s = _run(10_000, (0.0, 0.0, 0.0, 0.0), sign * frac * FSJ, C_m=5e-4, C_l=5e-4, backlash=backlash)
        assert np.all(s == 0.0)


def test_torque_above_breakaway_moves():
    s = _run(100, (0.0, 0.0, 0.0, 0.0), 1.01 * FSJ, backlash=0.0)
    assert s[-1, 1] > 0.0 and s[-1, 0] > 0.0


def test_motor_sees_only_its_own_inertia_inside_the_gap():
    """A torque that moves the motor by less than half the gap leaves the load still."""
    backlash = 2e-2
    T = 1.0
    # time to cover 0.4 * backlash from the centre with acceleration (T - FDJ)/J_m
    n = int(math.sqrt(2 * 0.4 * backlash * J_M / (T - FDJ)) / DT)
    s = _run(n, (0.0, 0.0, 0.0, 0.0), T, backlash=backlash)
    assert 0.0 < s[-1, 0] < 0.5 * backlash
    assert np.all(s[:, 2] == 0.0) and np.all(s[:, 3] == 0.0)          # load exactly still
    # the motor accelerates with its own inertia (first step breaks away at FSJ, then FDJ)
    expected = DT * (T - FSJ) / J_M + (n - 1) * DT * (T - FDJ) / J_M
    assert s[-1, 1] == pytest.approx(expected, rel=1e-9)


def test_gap_closes_then_the_bodies_move_together():
    backlash = 2e-3
    T = 0.5
    s = _run(3000, (0.0, 0.0, 0.0, 0.0), T, FSJ=0.0, FDJ=0.0, backlash=backlash)
    th_m, w_m, th_l, w_l = s.T
    moving = np.flatnonzero(w_l != 0.0)
    assert moving.size > 0
    first = moving[0]
    # the load starts when the motor has crossed half the gap
    assert th_m[first - 1] - th_l[first - 1] <= 0.5 * backlash
    assert th_m[first] - th_l[first] == pytest.approx(0.5 * backlash, rel=1e-9)
    # from contact on, one body: same speed, load on the gap's edge, acceleration T/(J_m+J_l)
    np.testing.assert_array_equal(w_m[first:], w_l[first:])
    np.testing.assert_allclose(th_m[first:] - th_l[first:], 0.5 * backlash, rtol=1e-9)
    np.testing.assert_allclose(np.diff(w_m[first + 1:]), DT * T / (J_M + J_L), rtol=1e-9)


@given(w0=st.floats(1.0, 100.0), w_l0=st.floats(-50.0, 50.0), J_m=inertia, J_l=inertia,
       backlash=st.floats(1e-5, 1e-2))
def test_momentum_is_conserved_at_impact(w0, w_l0, J_m, J_l, backlash):
    """Free bodies (no torque, no friction): the inelastic impact keeps J_m w_m + J_l w_l."""
    assume(w0 > w_l0 + 1e-3)
    half = 0.5 * backlash
    # the motor side sits just behind the contact and closes the gap in this step
    state = (half - 0.25 * (w0 - w_l0) * DT, w0, 0.0, w_l0)
    th_m, w_m, th_l, w_l = transmission_step(*state, 0.0, 0.0, J_m, 0.0, 0.0, 0.0, J_l, 0.0, backlash, 0.0, 0.0, DT)
    p0 = J_m * w0 + J_l * w_l0
    assert w_m == w_l
    assert J_m * w_m + J_l * w_l == pytest.approx(p0, rel=1e-12, abs=1e-15)
    assert w_m == pytest.approx(p0 / (J_m + J_l), rel=1e-12)
    assert th_m - th_l == pytest.approx(half, rel=1e-9)
    # kinetic energy is lost, never gained (inelastic)
    assert 0.5 * (J_m + J_l) * w_m ** 2 <= 0.5 * J_m * w0 ** 2 + 0.5 * J_l * w_l0 ** 2 + 1e-15


def test_zero_backlash_moves_as_one_body():
    T = 0.6
    n = 400
    s = _run(n, (0.0, 0.0, 0.0, 0.0), T, FSJ=0.0, FDJ=0.0, backlash=0.0)
    th_m, w_m, th_l, w_l = s.T
    np.testing.assert_array_equal(w_m, w_l)
    np.testing.assert_allclose(th_m, th_l, rtol=0, atol=1e-15)
    # acceleration T/(J_m + J_l) from the first step on
    np.testing.assert_allclose(w_m, np.arange(n + 1) * DT * T / (J_M + J_L), rtol=1e-12)
    # positions by the trapezoid rule on the speeds: exact for constant acceleration
    t = np.arange(n + 1) * DT
    np.testing.assert_allclose(th_m, 0.5 * T / (J_M + J_L) * t ** 2, rtol=1e-9, atol=1e-15)


def test_zero_backlash_with_friction_and_reversal_stays_coupled():
    T = np.where(np.arange(2000) < 1000, 0.8, -0.8)
    state = (0.0, 0.0, 0.0, 0.0)
    for Tk in T:
        state = transmission_step(*state, Tk, 0.0, J_M, 5e-4, FSJ, FDJ, J_L, 5e-4, 0.0, 0.0, 0.0, DT)
        assert state[1] == state[3]
        assert state[0] == pytest.approx(state[2], abs=1e-12)


def test_reversal_crosses_the_gap_with_a_lost_motion():
    """After a reversal the motor travels the whole gap before the load follows."""
    backlash = 1e-2
    state = (0.0, 0.0, 0.0, 0.0)
    hist = []
    for k in range(6000):
        Tm = 0.5 if k < 2000 else -0.5
        state = transmission_step(*state, Tm, 0.0, J_M, 5e-4, FSJ, FDJ, J_L, 5e-4, backlash, 0.0, 0.0, DT)
        hist.append(state)
    h = np.array(hist)
    gap = h[:, 0] - h[:, 2]
    assert gap.max() == pytest.approx(0.5 * backlash, rel=1e-9)
    assert gap.min() == pytest.approx(-0.5 * backlash, rel=1e-9)
    assert np.all(np.abs(gap) <= 0.5 * backlash * (1 + 1e-9))
    # the load is driven forward first, then backward
    assert h[:, 3].max() > 0.0 and h[:, 3].min() < 0.0


def test_python_and_compiled_versions_agree():
    rng = np.random.default_rng(5)
    for _ in range(200):
        args = (rng.normal(), rng.normal() * 50, rng.normal(), rng.normal() * 50, rng.normal() * 2,
                rng.normal() * 0.2, J_M, 5e-4, FSJ, FDJ, J_L, 5e-4, 1e-2 * rng.random(),
                4000.0 * rng.integers(0, 2), 0.5, DT)        # rigid or compliant contact
        assert transmission_step(*args) == transmission_step.py_func(*args)
        fa = (rng.normal() * 10 * rng.integers(0, 2), rng.normal(), FSJ, FDJ, J_M, DT)
        assert friction_step(*fa) == friction_step.py_func(*fa)


# --------------------------------------------------------------------------- compliant contact

K_C, D_C = 4000.0, 0.5
J_RED = J_M * J_L / (J_M + J_L)


def test_compliant_contact_rings_at_the_two_mass_frequency_at_the_mm_step():
    """Teeth pressed together (no backlash, no friction, no damping) and let go while both
    bodies turn at 100 rad/s (so that no speed crosses zero, where Borello's algorithm
    stops a body for a step): the gap oscillates at sqrt(K_c / J_red) / 2 pi = 513 Hz.
    Symplectic Euler at the MM's 125 us step (omega dt = 0.40) keeps the amplitude and
    runs 0.7 % fast (cos(w_d dt) = 1 - (omega dt)^2 / 2), within 1 %."""
    f_n = math.sqrt(K_C / J_RED) / (2 * math.pi)
    s = _run(4000, (1e-3, 100.0, 0.0, 100.0), 0.0, FSJ=0.0, FDJ=0.0, backlash=0.0, K_c=K_C)
    gap = s[:, 0] - s[:, 2]
    ups = np.flatnonzero((gap[:-1] < 0.0) & (gap[1:] >= 0.0))
    f = (len(ups) - 1) / ((ups[-1] - ups[0]) * DT)
    assert f == pytest.approx(f_n, rel=0.01)
    assert f > f_n                                                # the scheme's known bias
    assert np.abs(gap).max() < 1.1e-3 and np.abs(gap[-400:]).max() > 0.9e-3   # bounded, kept


@given(w=st.floats(80.0, 100.0), dw=st.floats(-5.0, 5.0), gap=st.floats(-2e-3, 2e-3),
       backlash=st.floats(0.0, 1e-3), D_c=st.floats(0.0, 2.0), sign=st.sampled_from([1.0, -1.0]))
def test_compliant_contact_conserves_momentum(w, dw, gap, backlash, D_c, sign):
    """No friction, viscous or external torque, speeds that keep their sign: the contact
    torque is internal, so J_m w_m + J_l w_l is kept to round-off, whatever the contact
    does (impacts, parting, ringing)."""
    s = _run(200, (gap, sign * (w + dw), 0.0, sign * w), 0.0, FSJ=0.0, FDJ=0.0,
             backlash=backlash, K_c=K_C, D_c=D_c)
    assert np.all(s[:, 1] * sign > 0.0)
    p = J_M * s[:, 1] + J_L * s[:, 3]
    assert np.abs(p - p[0]).max() <= 1e-13 * abs(p[0])


def test_compliant_contact_passes_no_torque_inside_the_gap():
    """Inside the dead band each body moves on its own, exactly as with the rigid contact."""
    a = _run(20, (0.0, 1.0, 0.0, 0.0), 0.5, FSJ=0.0, FDJ=0.0, backlash=0.2, K_c=K_C, D_c=D_C)
    assert np.all(a[:, 3] == 0.0)                                  # the load never moved
    assert a[-1, 1] == pytest.approx(1.0 + 20 * DT * 0.5 / J_M, rel=1e-12)


def test_the_mm_steps_the_contact_only_where_its_step_resolves_it():
    """The preset's contact at the MM's step: omega dt = 0.40, stepped compliant. A gear
    train 250 times stiffer (omega dt = 6.4) would make symplectic Euler blow up; the MM
    packs it as rigid instead, and simulates it."""
    from dataclasses import replace

    from emaphm.faults import scenario
    from emaphm.models.layout import P_D_C, P_K_C, contact_resolved, pack_shared
    from emaphm.models.monitoring import STATUS_OK, MonitoringModel
    from emaphm.params import siemens_1fk7060
    from emaphm.profiles import step

    p = siemens_1fk7060()
    assert math.sqrt(p.transmission.K_c / J_RED) * p.inverter.T_s == pytest.approx(0.40, abs=0.01)
    assert contact_resolved(p, p.inverter.T_s)
    P = pack_shared(p)
    assert (P[P_K_C], P[P_D_C]) == (p.transmission.K_c, p.transmission.D_c)
    stiff = replace(p, transmission=replace(p.transmission, K_c=1e6))
    assert not contact_resolved(stiff, stiff.inverter.T_s)
    assert pack_shared(stiff)[P_K_C] == 0.0
    assert contact_resolved(stiff, stiff.inverter.T_s / 8)         # sub-steps resolve it
    r = MonitoringModel(stiff, step(0.5, duration=0.1)).simulate(scenario("backlash-high"))
    assert r.status[0] == STATUS_OK and np.all(np.isfinite(r.i_abc))
