"""The monitoring model driven by the drive's recorded voltages (:mod:`emaphm.models.driven`):
known answers, the plant's own currents from its own voltages, failure as a value."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emaphm.models import driven
from emaphm.models.driven_simd import run
from emaphm.models.pmsm import back_emf_coeffs
from emaphm.problem import IdentificationProblem
from emaphm.simulate import simulate


@pytest.mark.parametrize("p,ecc", [(4, 0.0), (4, 0.3), (1, 0.3), (2, 0.5)])
def test_the_flux_linkage_is_the_antiderivative_of_the_back_emf_coefficients(p, ecc):
    c0 = (1.05, 0.98, 1.1)
    ecc_phase = 0.7
    h = 1e-6
    for theta in np.linspace(-3.0, 9.0, 13):
        up = np.array(driven.flux_linkage(theta + h, float(p), *c0, ecc, ecc_phase)[:3])
        down = np.array(driven.flux_linkage(theta - h, float(p), *c0, ecc, ecc_phase)[:3])
        want = back_emf_coeffs(theta, math.sin(p * theta), math.cos(p * theta), *c0, ecc, ecc_phase)
        np.testing.assert_allclose((up - down) / (2 * h), want, rtol=0, atol=1e-7)


def test_the_observer_places_both_poles_where_it_says():
    T_s = 1.25e-4
    l_1, l_2 = driven.observer_gains(T_s, 40.0)
    A = np.array([[1.0, T_s], [0.0, 1.0]])
    L = np.array([[l_1], [l_2]])
    err = (np.eye(2) - L @ np.array([[1.0, 0.0]])) @ A
    a = math.exp(-2 * math.pi * 40.0 * T_s)
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(err).real), [a, a], atol=1e-6)
    # a torque error Delta T leaves an innovation Delta T / (J omega_o^2): scale reads it in A
    J, k_T = 1.54e-3, 1.58
    assert driven.mechanical_scale(J, k_T, 40.0) * (0.1 / (J * (2 * math.pi * 40) ** 2)) == \
        pytest.approx(0.1 / k_T)


@pytest.fixture(scope="module")
def averaged_plant():
    """A noise-free plant trace of an averaged inverter (no PWM ripple) with its drive's log:
    the winding driven by those voltages is the plant's own winding."""
    return simulate(scenario="turn-short-15pct", pwm=False, drive_signals=True)


def test_the_plants_own_voltages_give_the_plants_own_currents(averaged_plant):
    k = np.asarray(averaged_plant.meta["k"])
    problem = IdentificationProblem(averaged_plant, fault_model="physical")
    model = problem.objective.model
    at = model.simulate(k).i_abc[0]
    np.testing.assert_allclose(at, model.i_meas, rtol=0, atol=0.02)    # of currents of 5 A
    healthy = model.simulate([0, 0, 0, 0, 0, 0, 0.5, 0.5]).i_abc[0]
    assert np.max(np.abs(healthy - model.i_meas)) > 0.5                # a 15 % short is amperes
    # and the mechanics follow the measured angle: the innovation is a few microradians
    assert np.max(np.abs(model.simulate(k).theta_m[0] - model.theta)) < 1e-3


def test_a_diverging_candidate_is_a_value_not_a_crash(averaged_plant):
    problem = IdentificationProblem(averaged_plant, fault_model="physical")
    obj = problem.objective
    K = np.tile(np.concatenate([[0, 0, 0, 0, 0, 0, 0.5, 0.5], np.zeros(len(problem.nuisance))]),
                (2, 1))
    P, CP = obj.model.pack(K)
    CP[1, :] = np.nan
    sse, status, _ = run(P, CP, obj.model._observer, obj.model.u, obj.model.theta,
                                obj.model._trig, 0.0,
                                obj.model.i_meas, obj.model.T_load, obj.weights,
                                obj.mech_weights, 0.04)
    assert status.tolist() == [0, 1]
    assert np.all(np.isfinite(sse[0])) and np.all(np.isinf(sse[1]))


# ------------------------------------------------------- the drive's loops from its references

PATHS = ("recorded voltages", "recorded current references", "recorded speed reference")


@pytest.fixture(scope="module")
def drive_log():
    """A plant trace with dead time and sensor noise whose drive logs its voltages and its
    current and speed references (a short in phase A, friction x2)."""
    from dataclasses import replace

    from emaphm.params import siemens_1fk7060
    from emaphm.simulate import DEFAULT_SENSORS

    p = siemens_1fk7060()
    plant = replace(p, inverter=replace(p.inverter, dead_time=1e-6, device_drop=1.0))
    return simulate(params=plant, sensors=DEFAULT_SENSORS, seed=2, drive_signals=True,
                    faults=["short_circuit:a:0.1:0.15", "friction:2"])


@pytest.mark.parametrize("path", PATHS)
def test_the_lanes_and_the_scalar_kernel_agree(drive_log, path):
    """The SIMD kernel (full blocks of lanes and a lone remainder) and the scalar one give
    the same sums and residuals to round-off on every path, a candidate gone astray
    included."""
    from dataclasses import replace

    from emaphm.params import siemens_1fk7060
    from emaphm.recorded import RecordedVoltageObjective

    obj = RecordedVoltageObjective.from_trace(drive_log, siemens_1fk7060(),
                                              fault_model="physical", drive_model=path)
    n_nu = len(obj.model.nuisance)
    rng = np.random.default_rng(5)
    K = np.column_stack([rng.random((17, 8)) * [1, 1, 0.2, 0.2, 0.2, 0.5, 1, 1],
                         rng.normal(0.0, 0.2, (17, n_nu)) + [6.0, 0.0, 1.0][:n_nu]])
    K[3, 0] = 40.0                                          # far outside: a value, not a crash
    lanes = obj.model
    scalar = replace(obj.model, kernel="scalar")
    for kw in ({}, {"residuals": True}, {"traces": True}):
        a_sse, a_st, a = lanes.run(K, obj.weights, obj.mech_weights, **kw)
        b_sse, b_st, b = scalar.run(K, obj.weights, obj.mech_weights, **kw)
        np.testing.assert_array_equal(a_st, b_st)
        np.testing.assert_allclose(a_sse, b_sse, rtol=1e-9)
        for name in a:
            np.testing.assert_allclose(a[name], b[name], rtol=1e-9, atol=1e-9)


def test_the_speed_loop_rebuilds_the_drives_current_reference():
    """Known answer: the speed loop on the drive's own speed reference and speed (every
    option of the speed loop in use) gives the q-current reference the drive logged, to the
    bit."""
    from dataclasses import replace

    from emaphm.models.controller import speed_loop_references
    from emaphm.models.layout import drive_settings
    from emaphm.params import siemens_1fk7060

    p = siemens_1fk7060()
    p = replace(p, controller=replace(p.controller, speed_filter_s=1e-3, torque_feedforward=1.0,
                                      current_reference_filter_s=2e-4,
                                      speed_reference_weight=0.7))
    tr = simulate(params=p, drive_signals=True, sensors=None, pwm=False)
    out = np.empty(tr.n)
    speed_loop_references(np.ascontiguousarray(tr.drive["omega_ref"]),
                          np.ascontiguousarray(tr.omega_m), np.ascontiguousarray(tr.theta_ref),
                          drive_settings(p), out)
    assert np.max(np.abs(tr.drive["i_q_ref"])) > 5.0
    np.testing.assert_array_equal(out, tr.drive["i_q_ref"])


@pytest.mark.parametrize("delay", [0, 1])
def test_the_drives_current_loop_gives_the_plants_own_currents(delay):
    """The current loop of the drive (its own delay) on the logged references, driving the
    true winding: the plant's currents; the healthy winding misses the 15 % short by
    amperes."""
    from dataclasses import replace

    from emaphm.params import siemens_1fk7060

    p = siemens_1fk7060()
    p = replace(p, controller=replace(p.controller, delay_periods=delay))
    tr = simulate(params=p, scenario="turn-short-15pct", pwm=False, drive_signals=True)
    tr = replace(tr, drive={"i_q_ref": tr.drive["i_q_ref"]})
    problem = IdentificationProblem(tr, params=p, fault_model="physical")
    assert problem.drive_model == "recorded current references"
    model = problem.objective.model
    k = np.asarray(tr.meta["k"])
    np.testing.assert_allclose(model.simulate(k).i_abc[0], model.i_meas, rtol=0, atol=0.02)
    healthy = model.simulate([0, 0, 0, 0, 0, 0, 0.5, 0.5]).i_abc[0]
    assert np.max(np.abs(healthy - model.i_meas)) > 0.5
