"""The NumPy-vectorised monitoring model agrees with the Numba kernel to round-off.

Both evaluate the same operations in the same order; they differ only in NumPy's
``sin``/``cos`` against libm (an ulp, now and then). How ill-conditioned candidates
are told apart and compared: ``tests/agreement.py``.
"""

import numpy as np
import pytest
from support import MIN_WELL, N_RANDOM, TOL, assert_traces_agree, conditioning, population

from emaphm.faults import SCENARIOS
from emaphm.models.layout import pack_population
from emaphm.models.monitoring import STATUS_DIVERGED, STATUS_TRIPPED, MonitoringModel
from monitoring_numpy import simulate_population_numpy, weighted_sse_numpy

K = population()
N_NAMED = len(SCENARIOS) + 2          # scenarios and corners, last in K


def _inputs(mm):
    """Command [rad] and load torque [N m] on the model's grid, as the kernel gets them."""
    return mm.profile.theta_ref(mm.t), mm.profile.load_torque(mm.t)


@pytest.fixture(scope="module", params=[1, 2], ids=["n_sub=1", "n_sub=2"])
def case(request):
    mm = MonitoringModel(n_sub=request.param)
    kernel, well, horizon = conditioning(mm, K)
    P, CP = mm.pack(K)
    vec = simulate_population_numpy(P, CP, *_inputs(mm), mm.n_sub)
    return mm, kernel, vec, well, horizon, (P, CP)


def test_named_scenarios_and_zero_corner_are_well_conditioned(case):
    _, _, _, well, _, _ = case
    assert well[-N_NAMED:-1].all()      # the all-ones corner diverges: not a round-off check
    assert well[:N_RANDOM].sum() >= MIN_WELL


def test_status_agrees(case):
    _, kernel, vec, _, _, _ = case
    np.testing.assert_array_equal(vec["status"], kernel.status)
    assert kernel.status[-1] == STATUS_TRIPPED        # the all-ones corner trips on overcurrent


def test_traces_agree_to_round_off(case):
    _, kernel, vec, well, horizon, _ = case
    assert_traces_agree(vec, kernel, well, horizon)


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


def test_tripped_corner_currents_die_out_in_both(case):
    _, kernel, vec, _, _, _ = case
    j = len(K) - 1                                      # all-ones corner: trips, then ASC
    for i_j in (kernel.i_abc[j], vec["i_abc"][j]):
        last = np.flatnonzero(np.any(i_j != 0.0, axis=1)).max()
        assert last < i_j.shape[0] - 1
        assert np.all(np.isfinite(i_j[:last + 1]))
        assert np.all(i_j[last + 1:] == 0.0)


def test_rejects_bad_input():
    mm = MonitoringModel()
    P, CP = pack_population(mm.params, K[:2])
    with pytest.raises(ValueError, match="n_sub must be an integer >= 1"):
        simulate_population_numpy(P, CP, *_inputs(mm), 0)
    with pytest.raises(ValueError, match=r"must have shape \(4000, 3\)"):
        weighted_sse_numpy(P, CP, *_inputs(mm), 1, np.zeros((10, 3)), np.ones((10, 3)))
