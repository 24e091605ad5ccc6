"""The reference plant: Crank-Nicolson winding circuit with fault loops, Stribeck friction
and a compliant backlash contact (emaphm.models.reference, emaphm.models.plant_mechanics).

Layers: the discrete energy identity of the trapezoidal rule (per sub-step on the real step
matrices, and in the kernel's bookkeeping); convergence order with the sub-step; limits that
reduce the plant to the healthy or the MM-style model; the fault loop's physics (it
dissipates, brakes, carries 10-30 A, ripples more with less leakage); friction that sticks
exactly; a contact that never pulls.

Measured numbers quoted in comments are from the default parameters and the 0.5 s
diagnostic profile (numpy 2.4, numba 0.68, x86-64).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from support import fitted_order, nrms, rms

from emaphm.faults import K_NOMINAL, scenario, scenario_fault_model
from emaphm.models.layout import contact_resolved
from emaphm.models.mechanics import transmission_step
from emaphm.models.plant_mechanics import (contact_torque, plant_step, stribeck_friction_step,
                                           stribeck_torque)
from emaphm.models.pmsm import back_emf_coeffs
from emaphm.models.reference import _run, electrical_step, run_reference
from emaphm.params import siemens_1fk7060
from emaphm.profiles import diagnostic, step

PARAMS = siemens_1fk7060()
PROFILE = diagnostic()
T_S = PARAMS.inverter.T_s
J_M, J_L = 7.7e-4, 7.7e-4
FSJ, FDJ = 0.12, 0.08


def shorted(mu: float, phase: int = 0) -> np.ndarray:
    k = K_NOMINAL.copy()
    k[2 + phase] = mu
    return k


def with_motor(**kw):
    return replace(PARAMS, motor=replace(PARAMS.motor, **kw))


def with_plant(**kw):
    """PARAMS with plant (Stribeck) and transmission (contact) fields replaced."""
    plant = {k: v for k, v in kw.items() if k == "omega_s"}
    trans = {k: v for k, v in kw.items() if k != "omega_s"}
    return replace(PARAMS, plant=replace(PARAMS.plant, **plant),
                   transmission=replace(PARAMS.transmission, **trans))


# =========================================================================== (a) energy identity

@pytest.mark.parametrize("mu", [[0.2, 0.0, 0.0], [0.05, 0.3, 0.1], [0.0, 0.0, 0.0]])
@pytest.mark.parametrize("h", [T_S / 128, T_S / 2, 1e-3])
def test_crank_nicolson_step_balances_energy_exactly(mu, h):
    """Per sub-step, on the kernel's own step matrices: with x_m the mean of start and end,
    h v.i_m = h x_m^T R_x x_m + h e.(T x_m) + [1/2 x^T L_x x], to round-off."""
    m = replace(PARAMS.motor, mu=tuple(mu), R_f=(0.05, 0.5, 0.15))
    el = electrical_step(m, h, "physical")
    assert el.A.shape == (2 + np.count_nonzero(mu),) * 2
    rng = np.random.default_rng(1)
    T = np.hstack([np.eye(3), -np.diag(el.mu)])
    for _ in range(20):
        z0 = rng.normal(0.0, 10.0, el.A.shape[0])
        v = rng.uniform(0.0, 600.0, 3)
        e = rng.normal(0.0, 100.0, 3)
        z1 = el.A @ z0 + el.B_v @ v - el.G @ e
        x0, x1 = el.S @ z0, el.S @ z1
        xm = 0.5 * (x0 + x1)
        d_mag = 0.5 * x1 @ el.L_x @ x1 - 0.5 * x0 @ el.L_x @ x0
        e_in = h * v @ xm[:3]
        e_loss = h * xm @ el.R_x @ xm
        e_ag = h * e @ (T @ xm)
        scale = abs(e_in) + e_loss + abs(e_ag) + abs(d_mag)
        assert abs(e_in - e_loss - e_ag - d_mag) < 1e-12 * scale
        assert abs(np.sum(x1[:3])) < 1e-12 * np.abs(x1[:3]).max()      # star connection


@pytest.mark.parametrize("n_sub", [2, 128])
@pytest.mark.parametrize("pwm", [True, False])
def test_kernel_energy_bookkeeping_closes_to_round_off(n_sub, pwm):
    """The kernel's cumulative energies with a fault loop on phase a (mu = 0.15) and b
    (0.05): input = copper and fault-loop loss + air-gap work + stored magnetic energy at
    every sample (measured max residual / E_in 1.1e-14 at n_sub = 2, 7e-13 at 128; the
    old exact-exponential scheme's first-order bookkeeping left 1e-4)."""
    k = K_NOMINAL.copy()
    k[2], k[3] = 0.15, 0.05
    r = run_reference(PARAMS, k, step(1.0, 0.005, 0.06), fault_model="physical", n_sub=n_sub,
                      pwm=pwm)
    E_in, E_loss, E_ag, E_mag = r["energy"].T
    assert E_in[-1] > 0.5 and E_loss[-1] > 0.3 and abs(E_ag[-1]) > 0.05 and E_mag.max() > 0.1
    assert np.all(np.diff(E_loss) >= 0.0) and np.all(E_mag >= 0.0)
    assert np.max(np.abs(E_in - E_loss - E_ag - E_mag)) < 1e-11 * E_in[-1]
    # the stored energy is 1/2 x^T L_x x of the sampled state, fault loops included
    el = electrical_step(replace(PARAMS.motor, mu=(0.15, 0.05, 0.0)), T_S / n_sub, "physical")
    x = np.hstack([r["i_abc"], r["i_fault"]])
    np.testing.assert_allclose(E_mag, 0.5 * np.einsum("ni,ij,nj->n", x, el.L_x, x),
                               rtol=1e-10, atol=1e-14)


def test_torque_includes_the_fault_loop():
    r = run_reference(PARAMS, shorted(0.2), PROFILE, fault_model="physical")
    m = PARAMS.motor
    for n in range(0, r["t"].size, 97):
        th = r["theta_m"][n]
        c = np.array(back_emf_coeffs(th, np.sin(m.p * th), np.cos(m.p * th), *m.c0, 0.0, 0.0))
        i, f = r["i_abc"][n], r["i_fault"][n]
        assert r["torque"][n] == pytest.approx(c @ i - 0.2 * c[0] * f[0], rel=1e-12, abs=1e-12)
    assert np.all(r["i_fault"][:, 1:] == 0.0)                    # no loop on healthy phases


# =========================================================================== (b) convergence

@pytest.mark.parametrize("name", ["nominal", "backlash-high", "turn-short-15pct"])
def test_plant_converges_at_first_order_with_the_sub_step(name):
    """Averaged inverter (pwm=False), n_sub = 8..128 against 512. Crank-Nicolson alone is
    second order, but the back-EMF is held at the sub-step start and the mechanics are
    symplectic Euler with Borello/Stribeck stops: the whole plant is first order (measured
    order 1.09 nominal, 0.96 backlash-high, 1.09 turn-short-15pct)."""
    k = scenario(name)
    fm = scenario_fault_model(name)
    ref = run_reference(PARAMS, k, PROFILE, fault_model=fm, n_sub=512, pwm=False)
    n_subs = np.array([8, 16, 32, 64, 128])
    errs = np.array([rms(run_reference(PARAMS, k, PROFILE, fault_model=fm, n_sub=int(n),
                                       pwm=False)["i_abc"] - ref["i_abc"]) for n in n_subs])
    order = fitted_order(T_S / n_subs, errs)
    assert 0.8 < order < 1.4, (name, order, errs)
    assert np.all(np.diff(errs) < 0), errs


def test_electrics_alone_converge_at_second_order():
    """The winding circuit under a fixed PWM-period input (standstill, no back-EMF): the
    Crank-Nicolson step is second order (measured 2.00)."""
    m = replace(PARAMS.motor, mu=(0.2, 0.0, 0.0))
    v = np.array([400.0, 100.0, 100.0])
    t_end = 2e-3

    def run(h):
        el = electrical_step(m, h, "physical")
        z = np.zeros(el.A.shape[0])
        for _ in range(round(t_end / h)):
            z = el.A @ z + el.B_v @ v
        return el.S @ z

    hs = np.array([2e-5, 1e-5, 5e-6, 2.5e-6])
    ref = run(1e-7)
    errs = np.array([np.abs(run(h) - ref).max() for h in hs])
    assert 1.9 < fitted_order(hs, errs) < 2.1, errs


# =========================================================================== (c) limits

def test_a_vanishing_fault_loop_gives_the_healthy_currents():
    """mu -> 0: the currents approach the healthy ones. The loop is driven by mu of the
    phase's EMF and acts back on the phase through mu of its MMF, so the effect falls
    like mu^2 once the small loop is resistive (measured NRMS 6.8e-3, 6.3e-5, 2.9e-7,
    2.3e-9 at mu = 1e-2 .. 1e-5: fitted order 2.18)."""
    healthy = run_reference(PARAMS, K_NOMINAL, PROFILE, fault_model="physical")["i_abc"]
    mus = np.array([1e-2, 1e-3, 1e-4, 1e-5])
    errs = np.array([nrms(run_reference(PARAMS, shorted(mu), PROFILE,
                                        fault_model="physical")["i_abc"], healthy) for mu in mus])
    assert np.all(np.diff(errs) < 0), errs
    assert 1.7 < fitted_order(mus, errs) < 2.6, errs
    assert errs[-1] < 1e-7


def test_leakage_has_no_effect_on_a_healthy_star_connected_motor():
    """Balanced windings: zero-sum currents see L whatever the leakage split, and the
    paper's uncoupled phases (sigma = 1) are the same motor (measured max differences
    6e-15 A, 1e-17 rad; 22 % NRMS between L_sigma 0.05 and 0.5 with mu = 0.2)."""
    base = run_reference(PARAMS, K_NOMINAL, PROFILE, fault_model="paper")
    for sigma in (0.02, 0.15, 0.6, 1.0):
        r = run_reference(with_motor(L_sigma=sigma), K_NOMINAL, PROFILE, fault_model="physical")
        np.testing.assert_allclose(r["i_abc"], base["i_abc"], rtol=0, atol=1e-8)
        np.testing.assert_allclose(r["theta_m"], base["theta_m"], rtol=0, atol=1e-10)
    # but on a faulty motor it matters: the check above can fail
    a = run_reference(with_motor(L_sigma=0.05), shorted(0.2), PROFILE, fault_model="physical")
    b = run_reference(with_motor(L_sigma=0.5), shorted(0.2), PROFILE, fault_model="physical")
    assert nrms(a["i_abc"], b["i_abc"]) > 1e-3


def test_stiff_contact_and_sharp_stribeck_approach_the_rigid_borello_mechanics():
    """K_c up (critically damped contact) and omega_s down: the plant's currents approach
    those of the same RM on the MM's mechanics with a rigid, momentum-conserving backlash
    (a contact too stiff for the step to resolve, which the MM steps as rigid) and
    two-level Borello friction (measured NRMS on backlash-high 8.5e-2 at the defaults,
    then 9.3e-3, 4.1e-3, 3.1e-3; the rest is the O(dt) difference of the two mechanical
    schemes)."""
    k = scenario("backlash-high")
    unresolved = with_plant(K_c=1e12)
    assert not contact_resolved(unresolved, T_S / 128)
    rigid = _run(unresolved, k, PROFILE, fault_model="paper", n_sub=128, pwm=True,
                 extra_load=0.0, mm_mechanics=True)["i_abc"]
    J_red = J_M * J_L / (J_M + J_L)
    errs = [nrms(run_reference(PARAMS, k, PROFILE)["i_abc"], rigid)]
    for K_c in (1e5, 1e6, 4e6):
        p = with_plant(omega_s=1e-4, K_c=K_c, D_c=2.0 * math.sqrt(K_c * J_red))
        errs.append(nrms(run_reference(p, k, PROFILE)["i_abc"], rigid))
    assert np.all(np.diff(errs) < 0), errs
    assert errs[0] > 0.02 and errs[-1] < 0.005, errs


def test_stiff_contact_mechanics_alone_approach_the_rigid_step():
    """Module level: a torque reversal through a 2e-2 rad gap, plant_step (K_c = 1e6,
    critically damped, omega_s = 1e-4) against transmission_step's rigid contact
    (``K_c = 0``; measured max motor
    angle difference 1.7e-4 rad over a 0.16 rad swing: the O(dt) difference of the two
    schemes at the impacts)."""
    dt = 1e-6
    J_red = J_M * J_L / (J_M + J_L)
    K_c, D_c = 1e6, 2.0 * math.sqrt(1e6 * J_red)
    a = b = (0.0, 0.0, 0.0, 0.0)
    th_a, th_b = [], []
    for n in range(60_000):
        T = 0.8 if n < 20_000 else -0.8
        a = plant_step(*a, T, 0.0, J_M, 5e-4, FSJ, FDJ, 1e-4, J_L, 5e-4, 2e-2, K_c, D_c, dt)
        b = transmission_step(*b, T, 0.0, J_M, 5e-4, FSJ, FDJ, J_L, 5e-4, 2e-2, 0.0, 0.0, dt)
        th_a.append(a[0])
        th_b.append(b[0])
    th_a, th_b = np.array(th_a), np.array(th_b)
    assert np.ptp(th_b) > 0.05
    assert np.abs(th_a - th_b).max() < 3e-4


# =========================================================================== (d) the fault loop

@pytest.mark.parametrize("mu", [0.1, 0.2, 0.3])
@pytest.mark.parametrize("R_f", [0.05, 0.15, 0.5])
def test_fault_loop_dissipates_brakes_and_carries_tens_of_amperes(mu, R_f):
    """On the diagnostic profile, phase a shorted: the loop dissipates (R_f f^2 > 0
    integrated), its MMF opposes the phase's (its torque -mu c_a f_a works against the
    motion), and it carries 5-14 A RMS over the ramp (19-27 A peak); the drive does
    not trip. Measured (R_f 0.05 / 0.15 / 0.5 ohm), ramp RMS and peak in A:
    mu 0.1: 11.7/27.4, 9.3/25.1, 5.3/19.4; mu 0.2: 12.8/26.3, 11.3/25.1, 7.8/21.8;
    mu 0.3: 13.3/25.1, 12.2/24.1, 9.3/22.0."""
    p = with_motor(R_f=R_f)
    r = run_reference(p, shorted(mu), PROFILE, fault_model="physical")
    healthy = run_reference(p, K_NOMINAL, PROFILE, fault_model="physical")
    f = r["i_fault"][:, 0]
    m = p.motor
    c_a = np.array([back_emf_coeffs(th, np.sin(m.p * th), np.cos(m.p * th), *m.c0, 0.0, 0.0)[0]
                    for th in r["theta_m"]])
    E_f = R_f * np.sum(f ** 2) * T_S                       # J, sampled
    W_loop = np.sum(-mu * c_a * f * r["omega_m"]) * T_S     # J, the loop torque's work
    ramp = (r["t"] >= 0.10) & (r["t"] < 0.25)
    assert r["trip_time"] is None
    assert E_f > 0.5
    assert W_loop < -1.0                                     # brakes
    assert 4.0 < rms(f[ramp]) < 15.0 and 15.0 < np.abs(f).max() < 30.0
    # the drive pays for it: more loss than the healthy motor on the same profile
    assert r["energy"][-1, 1] > healthy["energy"][-1, 1] + E_f / 2


def test_fault_loop_is_driven_by_the_back_emf():
    """At standstill under a DC current the loop current decays to zero (no EMF in the
    shorted turns), and it grows with speed."""
    r = run_reference(PARAMS, shorted(0.2), PROFILE, fault_model="physical")
    f, w, t = r["i_fault"][:, 0], r["omega_m"], r["t"]
    hold = (t > 0.08) & (t < 0.10)                         # settled after the first step
    ramp = (t > 0.15) & (t < 0.24)                         # 63 rad/s
    assert rms(f[hold]) < 0.05 * rms(f[ramp])
    assert np.abs(w[ramp]).min() > 40.0


# =========================================================================== (e) leakage and ripple

def test_fault_loop_ripple_grows_as_leakage_shrinks():
    """The shorted turns are coupled to the phase through everything but their leakage:
    the less leakage, the larger the PWM ripple the loop carries (measured RMS of the
    within-period ripple 0.086, 0.19, 0.51, 1.25 A at L_sigma = 0.5, 0.15, 0.05, 0.02).
    Without switching what is left is the loop's response to the controller's voltage
    steps (measured 0.26 A at L_sigma = 0.02, a fifth of the PWM case)."""
    sigmas = [0.5, 0.15, 0.05, 0.02]
    ripple = [rms(run_reference(with_motor(L_sigma=s), shorted(0.15), PROFILE,
                                fault_model="physical")["i_fault_ripple"][:, 0]) for s in sigmas]
    assert np.all(np.diff(ripple) > 0), ripple
    assert ripple[-1] > 5 * ripple[0], ripple
    averaged = run_reference(with_motor(L_sigma=0.02), shorted(0.15), PROFILE,
                             fault_model="physical", pwm=False)["i_fault_ripple"][:, 0]
    assert rms(averaged) < 0.3 * ripple[-1]


# =========================================================================== (f) Stribeck friction

@given(frac=st.floats(0.0, 1.0), FS=st.floats(0.0, 2.0), ratio=st.floats(0.0, 1.0),
       w_s=st.floats(1e-3, 10.0), J=st.floats(1e-5, 1e-2), dt=st.floats(1e-7, 1e-3))
def test_stribeck_body_at_rest_under_static_limit_stays_exactly_still(frac, FS, ratio, w_s, J, dt):
    for sign in (1.0, -1.0):
        assert stribeck_friction_step(0.0, sign * frac * FS, FS, ratio * FS, w_s, J, dt) == 0.0


@pytest.mark.parametrize("backlash", [0.0, 2e-4, 2e-2])
@pytest.mark.parametrize("frac", [0.0, 0.5, 0.999, 1.0])
def test_plant_under_torque_below_breakaway_never_moves(backlash, frac):
    for sign in (1.0, -1.0):
        s = (0.0, 0.0, 0.0, 0.0)
        for _ in range(20_000):
            s = plant_step(*s, sign * frac * FSJ, 0.0, J_M, 5e-4, FSJ, FDJ, 1.0, J_L, 5e-4,
                           backlash, 4000.0, 0.5, 1e-6)
            assert s == (0.0, 0.0, 0.0, 0.0)
    # just above breakaway it moves: the check can fail
    s = plant_step(0.0, 0.0, 0.0, 0.0, 1.01 * FSJ, 0.0, J_M, 5e-4, FSJ, FDJ, 1.0, J_L, 5e-4,
                   backlash, 4000.0, 0.5, 1e-6)
    assert s[1] > 0.0


def test_stribeck_level_falls_from_static_to_dynamic():
    w = np.array([0.0, 0.5, 1.0, 2.0, 5.0])
    T = np.array([stribeck_torque(x, FSJ, FDJ, 1.0) for x in w])
    np.testing.assert_allclose(T, FDJ + (FSJ - FDJ) * np.exp(-w ** 2), rtol=1e-15)
    assert T[0] == FSJ and np.all(np.diff(T) < 0) and T[-1] == pytest.approx(FDJ, abs=1e-12)
    assert stribeck_torque(-1.0, FSJ, FDJ, 1.0) == T[2]          # a magnitude
    # moving at w: one explicit step with the Stribeck level
    dt = 1e-5
    assert stribeck_friction_step(1.0, 0.3, FSJ, FDJ, 1.0, J_M, dt) == pytest.approx(
        1.0 + dt * (0.3 - T[2]) / J_M, rel=1e-14)
    assert stribeck_friction_step(-1.0, -0.3, FSJ, FDJ, 1.0, J_M, dt) == pytest.approx(
        -1.0 - dt * (0.3 - T[2]) / J_M, rel=1e-14)
    # a speed that would cross zero stops exactly
    assert stribeck_friction_step(1e-4, -1.0, FSJ, FDJ, 1.0, J_M, dt) == 0.0


# =========================================================================== (g) contact

@given(gap=st.floats(-0.05, 0.05), rate=st.floats(-500.0, 500.0), backlash=st.floats(0.0, 0.02),
       K_c=st.floats(0.0, 1e7), D_c=st.floats(0.0, 100.0))
def test_contact_never_pulls(gap, rate, backlash, K_c, D_c):
    T = contact_torque(gap, rate, backlash, K_c, D_c)
    half = 0.5 * backlash
    if gap > half:
        assert T >= 0.0
    elif gap < -half:
        assert T <= 0.0
    else:
        assert T == 0.0


def test_bodies_parting_after_an_impact_are_never_pulled_together():
    """A motor thrown against a free load through the default contact (damping ratio
    0.2): as the bodies part, the damper term outweighs the relaxing spring and the
    unclipped spring-damper would pull (it does at some step); the contact torque stays
    >= 0 and the load leaves faster than the motor (a partly elastic impact)."""
    K_c, D_c, backlash, dt = 4000.0, 0.5, 2e-4, 1e-6
    s = (0.5 * backlash, 20.0, 0.0, 0.0)                   # at the edge, closing at 20 rad/s
    would_pull = False
    for _ in range(5000):
        gap, rate = s[0] - s[2], s[1] - s[3]
        if gap > 0.5 * backlash:
            raw = K_c * (gap - 0.5 * backlash) + D_c * rate
            would_pull |= raw < 0.0
            assert contact_torque(gap, rate, backlash, K_c, D_c) >= 0.0
        s = plant_step(*s, 0.0, 0.0, J_M, 0.0, 0.0, 0.0, 1.0, J_L, 0.0, backlash, K_c, D_c, dt)
    assert would_pull
    assert s[3] > s[1]                                     # parted: the load runs ahead
    # momentum is only exchanged, not created (no friction, no viscous terms)
    assert J_M * s[1] + J_L * s[3] == pytest.approx(J_M * 20.0, rel=1e-9)


def test_contact_resonance_near_500_hz_and_stable_without_damping():
    """Zero backlash and no damper: the contact is a linear torsion spring between the two
    inertias. Symplectic Euler at the plant's 1 us step keeps the undamped oscillation
    bounded (an explicit Euler would grow it by 1 + (omega dt)^2 / 2 per step) at the
    two-mass frequency sqrt(K_c / J_red) / 2 pi = 513 Hz."""
    J_red = J_M * J_L / (J_M + J_L)
    dt = T_S / 128
    s = (1e-4, 0.0, 0.0, 0.0)                               # twisted by 1e-4 rad
    twist = np.empty(40_000)                                # 5 ms, about 2.5 periods
    for n in range(twist.size):
        s = plant_step(*s, 0.0, 0.0, J_M, 0.0, 0.0, 0.0, 1.0, J_L, 0.0, 0.0, 4000.0, 0.0, dt)
        twist[n] = s[0] - s[2]
    assert np.abs(twist).max() < 1e-4 * (1 + 1e-3)
    assert np.abs(twist[-10_000:]).max() > 1e-4 * (1 - 1e-3)            # not damped either
    up = np.flatnonzero((twist[:-1] < 0) & (twist[1:] >= 0))            # upward zero crossings
    f_meas = 1.0 / (np.mean(np.diff(up)) * dt)
    f_n = math.sqrt(4000.0 / J_red) / (2 * math.pi)
    assert f_meas == pytest.approx(f_n, rel=1e-3)
    assert 500.0 < f_n < 530.0


@pytest.mark.parametrize("extra", [0.0, 0.5])
def test_extra_load_is_a_constant_load_torque(extra):
    from emaphm.profiles import Constant, Profile
    loaded = Profile(PROFILE.duration, PROFILE.command, (Constant(0.5),))
    a = run_reference(PARAMS, K_NOMINAL, PROFILE, extra_load=extra)
    b = run_reference(PARAMS, K_NOMINAL, loaded if extra else PROFILE)
    np.testing.assert_array_equal(a["i_abc"], b["i_abc"])
    if extra:
        c = run_reference(PARAMS, K_NOMINAL, PROFILE)
        assert nrms(a["i_abc"], c["i_abc"]) > 0.01


def test_arguments_are_validated():
    with pytest.raises(ValueError, match="unknown fault model"):
        run_reference(PARAMS, K_NOMINAL, PROFILE, fault_model="simulink")
    with pytest.raises(ValueError, match="extra_load"):
        run_reference(PARAMS, K_NOMINAL, PROFILE, extra_load=float("nan"))
    with pytest.raises(ValueError, match="n_sub must be an even integer"):
        run_reference(PARAMS, K_NOMINAL, PROFILE, n_sub=3)
