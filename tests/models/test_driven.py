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
