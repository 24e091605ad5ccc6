"""The monitoring model's physical inter-turn short circuit (``fault_model="physical"``).

A shorted fraction ``mu`` of a phase's turns carries a fault-loop current through the
fault resistance ``R_f`` (:mod:`emaphm.models.windings`). Layers: the winding step
against a direct integration of the windings ODE (scipy); the loop current flows in
the shorted phase only and leaves a phase-specific signature; severity grows with mu,
falls with R_f and vanishes continuously as mu -> 0; the NumPy baseline agrees with
the kernel under this fault model; misuse raises.

Measured numbers quoted in comments are from the default parameters (R_f = 0.15 ohm,
L_sigma = 0.15) and the 0.5 s diagnostic profile.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support import (MIN_WELL, N_RANDOM, TOL, assert_traces_agree, conditioning, nrms,
                     population)
from scipy.integrate import solve_ivp

from emaphm.faults import K_NOMINAL, FaultVectorError, apply_faults, scenario
from emaphm.models.layout import C_GAMMA, C_MU_A, C_PHI, MU_MIN, pack, pack_population
from emaphm.models.monitoring import (STATUS_DIVERGED, STATUS_OK, MonitoringModel, _kernel,
                                      simulate_reference)
from monitoring_numpy import simulate_population_numpy, weighted_sse_numpy
from emaphm.models.pmsm import (back_emf_coeffs, phase_currents, torque_loops, winding_input,
                                winding_step)
from emaphm.models.windings import Q, reduced, winding_matrices
from emaphm.params import siemens_1fk7060
from emaphm.profiles import diagnostic

PARAMS = siemens_1fk7060()
PROFILE = diagnostic()
MM = MonitoringModel(PARAMS, PROFILE, fault_model="physical")


def shorted(mus, phase: int = 0) -> np.ndarray:
    """Nominal k with ``k[2 + phase]`` (the shorted fraction) set to each of ``mus``."""
    K = np.tile(K_NOMINAL, (len(mus), 1))
    K[:, 2 + phase] = mus
    return K


def with_fault_resistance(R_f: float):
    return replace(PARAMS, motor=replace(PARAMS.motor, R_f=(R_f,) * 3))


# =========================================================================== the winding step

@pytest.mark.parametrize("fault_model, k", [
    ("physical", scenario("turn-short-15pct")),
    ("physical", np.array([0, 0, 0.02, 0.3, 0.0, 0.1, 0.2, 0.5])),      # two loops, stiff one
    ("paper", scenario("short-circuit-high")),
])
def test_winding_step_equals_direct_integration_of_the_windings_ode(fault_model, k):
    """One step of the kernel's update (``winding_input`` -> ``winding_step`` ->
    ``phase_currents``) from a random state with random held leg voltages and back-EMF
    equals scipy's stiff integration of ``L_x dx/dt = -R_x x + v - T^T c omega``
    (x = [i_abc, f], star point eliminated by i = Q y) over the same step."""
    faulty = apply_faults(PARAMS, k, fault_model)
    m = faulty.motor
    for n_sub in (1, 4):
        P, cp = pack(faulty, fault_model=fault_model, n_sub=n_sub)
        dt = PARAMS.inverter.T_s / n_sub
        sigma = 1.0 if fault_model == "paper" else m.L_sigma
        mu = np.where(np.array(m.mu) < MU_MIN, 0.0, m.mu)
        L_r, R_r = reduced(*winding_matrices(m.R, m.L, sigma, mu, m.R_f), mu)
        rng = np.random.default_rng(n_sub)
        for _ in range(3):
            z = rng.normal(0.0, 3.0, 5)
            z[2:] *= mu > 0                                   # no loop, no loop current
            u = rng.uniform(0.0, PARAMS.inverter.V_dc, 3)
            e = rng.normal(0.0, 50.0, 3)
            # the ODE's input, built from the circuit's matrices, not from winding_input
            T = np.hstack([np.eye(3), -np.diag(mu)])
            S = np.zeros((6, 5))
            S[:3, :2] = Q
            S[3:, 2:] = np.eye(3)
            w_ode = S.T @ (np.r_[u, 0, 0, 0] - T.T @ e)
            w = winding_input(*u, *e, *cp[0, C_MU_A:C_MU_A + 3])
            np.testing.assert_allclose(w, w_ode, rtol=1e-12, atol=1e-12)
            sol = solve_ivp(lambda t, x: np.linalg.solve(L_r, w_ode - R_r @ x), (0.0, dt), z,
                            method="Radau", rtol=1e-12, atol=1e-12,
                            jac=-np.linalg.solve(L_r, R_r))
            z1 = winding_step(*z, *w, tuple(cp[0, C_PHI:C_GAMMA]), tuple(cp[0, C_GAMMA:C_GAMMA + 25]))
            np.testing.assert_allclose(z1, sol.y[:, -1], rtol=1e-7, atol=1e-9)
            np.testing.assert_allclose(phase_currents(z1[0], z1[1]), Q @ np.array(z1[:2]),
                                       rtol=1e-14, atol=1e-14)


def test_torque_with_a_fault_loop_is_the_mmf_currents_times_c():
    """``T_m = sum_j c_j (i_j - mu_j f_j)``: the loop's MMF opposes the phase's. Checked on
    the readable loop's traces (the kernel equals it to round-off)."""
    k = scenario("turn-short-15pct")
    r = simulate_reference(PARAMS, k, PROFILE, fault_model="physical")
    m = apply_faults(PARAMS, k, "physical").motor
    for n in (0, 500, 1777, 3999):
        th = r["theta_m"][n]
        c = back_emf_coeffs.py_func(th, np.sin(m.p * th), np.cos(m.p * th), *m.c0, m.ecc,
                                    m.ecc_phase)
        i, f = r["i_abc"][n], r["f_abc"][n]
        expected = sum(c[j] * (i[j] - m.mu[j] * f[j]) for j in range(3))
        assert r["torque"][n] == pytest.approx(expected, rel=1e-12, abs=1e-12)
        assert torque_loops.py_func(*i, *f, *c, *m.mu) == r["torque"][n]


# =========================================================================== the fault signature

def test_short_on_phase_a_drives_a_loop_current_in_phase_a_only():
    k = scenario("turn-short-15pct")
    r = simulate_reference(PARAMS, k, PROFILE, fault_model="physical")
    f = r["f_abc"]
    assert np.sqrt(np.mean(f[:, 0] ** 2)) > 1.0            # A rms (measured 7.3 A)
    assert not f[:, 1:].any()                              # b and c have no loop
    # the kernel runs the same loop: its phase currents equal the readable loop's
    np.testing.assert_allclose(MM.simulate(k).i_abc[0], r["i_abc"], rtol=0, atol=1e-9)
    # the paper's model has no loop at all
    assert not simulate_reference(PARAMS, k, PROFILE, fault_model="paper")["f_abc"].any()


def test_short_circuit_signature_is_specific_to_the_shorted_phase():
    """The same short on a, b or c: pairwise different currents (measured NRMS 18 to 19 %),
    and the shorted phase's own current changes most against the healthy run."""
    K = np.vstack([K_NOMINAL] + [shorted([0.1], phase) for phase in range(3)])
    i = MM.simulate_population(K).i_abc
    healthy = i[0]
    for a in range(1, 4):
        for b in range(a + 1, 4):
            assert nrms(i[a], i[b]) > 0.05, (a, b)
    for phase in range(3):
        change = np.sqrt(np.mean((i[1 + phase] - healthy) ** 2, axis=0))
        assert np.argmax(change) == phase, (phase, change)


def test_severity_grows_with_the_shorted_fraction():
    """NRMS change of the currents against healthy, R_f fixed (measured 0.7 %, 2.3 %,
    9.9 %, 26 %, 63 %, 139 % for mu = 0.01 ... 0.4)."""
    mus = [0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4]
    r = MM.simulate_population(shorted(mus))
    assert (r.status == STATUS_OK).all()
    sev = np.array([nrms(r.i_abc[j], r.i_abc[0]) for j in range(len(mus))])
    assert sev[0] == 0.0
    assert np.all(np.diff(sev) > 0), sev


def test_severity_falls_as_the_fault_resistance_grows():
    """A short across more resistance is a weaker fault (measured at mu = 0.1: 36 %, 26 %,
    15 %, 6.8 %, 2.4 %, 0.25 % for R_f = 0.01 ... 50 ohm)."""
    sev = []
    for R_f in (0.01, 0.15, 0.5, 1.5, 5.0, 50.0):
        r = MonitoringModel(with_fault_resistance(R_f), PROFILE,
                            fault_model="physical").simulate_population(shorted([0.0, 0.1]))
        sev.append(nrms(r.i_abc[1], r.i_abc[0]))
    assert np.all(np.diff(sev) < 0), sev
    assert sev[-1] < 0.01 < 0.1 < sev[0]


def test_vanishing_short_converges_to_healthy():
    """mu -> 0: the change of the currents vanishes continuously, as mu^2 (the loop's EMF
    and its MMF on the phase both scale with mu); at mu = 0 the physical model is the
    healthy motor, the paper model's nominal run to round-off."""
    mus = np.array([1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4])
    r = MM.simulate_population(shorted(np.r_[0.0, mus]))
    change = np.array([nrms(r.i_abc[1 + j], r.i_abc[0]) for j in range(mus.size)])
    assert np.all(np.diff(change) < 0), change
    order = np.polyfit(np.log(mus[2:]), np.log(change[2:]), 1)[0]
    assert 1.7 < order < 2.3, (order, change)
    paper = MonitoringModel(PARAMS, PROFILE).simulate(K_NOMINAL)
    np.testing.assert_allclose(r.i_abc[0], paper.i_abc[0], rtol=0, atol=1e-9)


# =========================================================================== NumPy baseline

K_POP = population()


@pytest.fixture(scope="module", params=[1, 2], ids=["n_sub=1", "n_sub=2"])
def numpy_case(request):
    mm = MonitoringModel(n_sub=request.param, fault_model="physical")
    kernel, well, horizon = conditioning(mm, K_POP)
    P, CP = mm.pack(K_POP)
    vec = simulate_population_numpy(P, CP, mm._ref, mm._load, mm.n_sub)
    return mm, kernel, vec, well, horizon, (P, CP)


def test_numpy_baseline_agrees_under_the_physical_model(numpy_case):
    mm, kernel, vec, well, horizon, (P, CP) = numpy_case
    assert well[:N_RANDOM].sum() >= MIN_WELL
    np.testing.assert_array_equal(vec["status"], kernel.status)
    assert_traces_agree(vec, kernel, well, horizon)
    rng = np.random.default_rng(5)
    i_target = kernel.i_abc[N_RANDOM] + 0.05 * rng.standard_normal(kernel.i_abc.shape[1:])
    weights = rng.uniform(0.5, 2.0, size=i_target.shape)
    f_kernel, s_kernel = mm.weighted_sse(K_POP, i_target, weights)
    f_vec, s_vec = weighted_sse_numpy(P, CP, mm._ref, mm._load, mm.n_sub, i_target, weights)
    np.testing.assert_array_equal(s_vec, s_kernel)
    ok = well & (s_kernel == STATUS_OK)
    np.testing.assert_allclose(f_vec[ok], f_kernel[ok], rtol=TOL)


# =========================================================================== misuse

def test_misuse_raises():
    with pytest.raises(FaultVectorError, match="unknown fault model"):
        MonitoringModel(PARAMS, PROFILE, fault_model="ideal")
    mm = MonitoringModel(PARAMS, PROFILE, n_sub=2, fault_model="physical")
    P, CP = pack_population(PARAMS, shorted([0.1]), fault_model="physical")     # n_sub = 1
    n = mm.t.size
    with pytest.raises(ValueError, match="another n_sub"):
        _kernel(P, CP, mm._ref, mm._load, 2, np.zeros((0, 3)), np.zeros((0, 3)),
                np.zeros((1, n, 3)), np.zeros((1, n)), np.zeros((1, n)), np.zeros((1, n)),
                np.zeros(1), np.zeros(1, dtype=np.int64), np.zeros((0, 0, 3)))
    with pytest.raises(ValueError, match="another n_sub"):
        simulate_population_numpy(P, CP, mm._ref, mm._load, 2)
    # a non-finite candidate is a value, not an exception, under this model too
    K = np.vstack([shorted([0.1]), np.full(8, np.nan)])
    fit, status = MM.weighted_sse(K, np.zeros((MM.t.size, 3)), np.ones((MM.t.size, 3)))
    assert status.tolist() == [STATUS_OK, STATUS_DIVERGED] and np.isinf(fit[1])
