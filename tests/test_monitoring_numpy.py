"""The NumPy-vectorised monitoring model agrees with the Numba kernel to round-off.

Both evaluate the same operations in the same order; they differ only in
NumPy's ``sin``/``cos`` against libm (an ulp, now and then). Most trajectories
carry such differences through unchanged, and there the two must agree to
1e-9. Some candidates with a heavily shorted phase (k3..k5 above about 0.7)
drive the discrete current loop unstable: the currents alternate in sign from
one control period to the next, grow by a factor of 3 to 15 per period and
settle in a limit cycle of up to +-1000 A bounded by the voltage limit. Such a
trajectory amplifies any ulp, so the kernel does not even agree with its own
"twin", the same run with ``k`` nudged by 1e-12 (relative). For those we check
what is well defined: the same status, and agreement up to the step where the
twin departs (the horizon of predictability), less ``MARGIN`` steps since the
nudge is larger than an ulp. The kernel decides which candidates are
ill-conditioned, so a wrong branch in either implementation cannot hide behind
that label on a well-conditioned candidate.
"""

import numpy as np
import pytest

from emaphm.faults import SCENARIOS
from emaphm.models.layout import pack_population
from emaphm.models.monitoring import STATUS_DIVERGED, STATUS_TRIPPED, MonitoringModel
from emaphm.models.monitoring_numpy import simulate_population_numpy, weighted_sse_numpy

TOL = 1e-9            # rtol and atol on currents [A], angles [rad], speeds [rad/s], torque [N m]
NUDGE = 1e-12         # relative nudge of k that makes the kernel's twin
MARGIN = 10           # steps: growth of a ~1e4 ulp nudge over an ulp one, at a gain of ~3/step
N_RANDOM = 24


def _population():
    rng = np.random.default_rng(20240611)
    named = np.array([k for k in SCENARIOS.values()])
    corners = np.array([np.zeros(8), np.ones(8)])
    return np.vstack([rng.random((N_RANDOM, 8)), named, corners])


K = _population()
N_NAMED = len(SCENARIOS) + 2          # scenarios and corners, last in K


def _inputs(mm):
    """Command [rad] and load torque [N m] on the model's grid, as the kernel gets them."""
    return mm.profile.theta_ref(mm.t), mm.profile.load_torque(mm.t)


def _traces(r):
    return {"i_abc": r.i_abc, "theta_m": r.theta_m, "omega_m": r.omega_m, "torque": r.torque}


@pytest.fixture(scope="module", params=[1, 2], ids=["n_sub=1", "n_sub=2"])
def case(request):
    mm = MonitoringModel(n_sub=request.param)
    kernel = mm.simulate_population(K)
    twin = mm.simulate_population(K + NUDGE * (0.5 - K))     # stays inside [0, 1]
    # per candidate: first step where the kernel departs from its nudged twin by > TOL
    dev = np.max(np.abs(kernel.i_abc - twin.i_abc), axis=2)
    departs = dev > TOL
    horizon = np.where(departs.any(axis=1), departs.argmax(axis=1), mm.t.size)
    well = horizon == mm.t.size
    P, CP = pack_population(mm.params, K)
    vec = simulate_population_numpy(P, CP, *_inputs(mm), mm.n_sub)
    return mm, kernel, vec, well, horizon, (P, CP)


def test_named_scenarios_and_zero_corner_are_well_conditioned(case):
    _, _, _, well, _, _ = case
    assert well[-N_NAMED:-1].all()      # the all-ones corner diverges: not a round-off check
    assert well[:N_RANDOM].sum() >= N_RANDOM // 2


def test_status_agrees(case):
    _, kernel, vec, _, _, _ = case
    np.testing.assert_array_equal(vec["status"], kernel.status)
    assert kernel.status[-1] == STATUS_TRIPPED        # the all-ones corner trips on overcurrent


def test_traces_agree_to_round_off_on_well_conditioned_candidates(case):
    _, kernel, vec, well, _, _ = case
    for name, ref in _traces(kernel).items():
        np.testing.assert_allclose(vec[name][well], ref[well], rtol=TOL, atol=TOL, err_msg=name)


def test_traces_agree_up_to_the_kernels_own_horizon_elsewhere(case):
    _, kernel, vec, well, horizon, _ = case
    for j in np.flatnonzero(~well):
        h = max(horizon[j] - MARGIN, 0)
        for name, ref in _traces(kernel).items():
            np.testing.assert_allclose(vec[name][j, :h], ref[j, :h], rtol=TOL, atol=TOL,
                                       err_msg=f"{name}, candidate {j}, first {h} steps")


def test_weighted_sse_agrees(case):
    mm, kernel, _, well, _, (P, CP) = case
    rng = np.random.default_rng(5)
    i_target = kernel.i_abc[N_RANDOM] + 0.05 * rng.standard_normal(kernel.i_abc.shape[1:])
    weights = rng.uniform(0.5, 2.0, size=i_target.shape)
    f_kernel, s_kernel = mm.weighted_sse(K, i_target, weights)
    f_vec, s_vec = weighted_sse_numpy(P, CP, *_inputs(mm), mm.n_sub, i_target, weights)
    np.testing.assert_array_equal(s_vec, s_kernel)
    dead = s_vec == STATUS_DIVERGED
    assert np.all(np.isinf(f_vec[dead])) and np.all(np.isinf(f_kernel[dead]))
    assert np.all(np.isfinite(f_kernel[~dead]))          # a tripped drive still has a fitness
    ok = well & (s_kernel == 0)
    np.testing.assert_allclose(f_vec[ok], f_kernel[ok], rtol=TOL)
    assert np.all(np.isfinite(f_vec[s_vec == 0]))


def test_diverged_candidate_traces_stop_and_stay_zero(case):
    _, kernel, vec, _, _, _ = case
    j = len(K) - 1                                      # all-ones corner
    for traces in (kernel.i_abc[j], vec["i_abc"][j]):
        last = np.flatnonzero(np.any(traces != 0.0, axis=1)).max()
        assert last < traces.shape[0] - 1
        assert np.all(np.isfinite(traces[:last + 1]))
        assert np.all(traces[last + 1:] == 0.0)


def test_rejects_bad_input():
    mm = MonitoringModel()
    P, CP = pack_population(mm.params, K[:2])
    with pytest.raises(ValueError, match="n_sub must be an integer >= 1"):
        simulate_population_numpy(P, CP, *_inputs(mm), 0)
    with pytest.raises(ValueError, match=r"must have shape \(4000, 3\)"):
        weighted_sse_numpy(P, CP, *_inputs(mm), 1, np.zeros((10, 3)), np.ones((10, 3)))
