"""The SIMD monitoring kernel agrees with the scalar kernel to round-off.

:mod:`emaphm.models.monitoring_simd` evaluates the same operations in the same
order as :func:`emaphm.models.monitoring._kernel`; the one difference is its
branch-free sine and cosine (fdlibm's, within 1 ulp) against libm's, which
differ by an ulp now and then. How ill-conditioned candidates (heavily shorted
phases, whose discrete current loop is unstable until the drive trips) are told
apart and compared: ``tests/agreement.py``.
"""

import math

import numpy as np
import pytest
from support import MIN_WELL, N_RANDOM, TOL, assert_traces_agree, conditioning, population, traces

from emaphm.faults import SCENARIOS
from emaphm.models.layout import C_KP, C_PHI, P_THETA0, pack_population
from emaphm.models.monitoring import STATUS_DIVERGED, STATUS_OK, MonitoringModel
from emaphm.models.monitoring_simd import LANES, TRIG_LIMIT, _kernel, sincos

K = population()

#: no fault-loop currents asked of a kernel
NO_LOOPS = np.zeros((0, 0, 3))


def _inputs(mm):
    """Command [rad] and load torque [N m] on the model's grid, as the kernel gets them."""
    return (np.ascontiguousarray(mm.profile.theta_ref(mm.t)),
            np.ascontiguousarray(mm.profile.load_torque(mm.t)))


def simd_traces(mm, P, CP):
    """What ``MonitoringModel.simulate_population`` returns, from the SIMD kernel."""
    n_pop, n = CP.shape[0], mm.t.size
    out_i = np.zeros((n_pop, n, 3))
    th, om, tq = (np.zeros((n_pop, n)) for _ in range(3))
    fitness = np.zeros(n_pop)
    status = np.zeros(n_pop, dtype=np.int64)
    empty = np.zeros((0, 3))
    _kernel(P, CP, *_inputs(mm), mm.n_sub, empty, empty, out_i, th, om, tq, fitness, status,
            NO_LOOPS)
    return {"i_abc": out_i, "theta_m": th, "omega_m": om, "torque": tq, "status": status,
            "fitness": fitness}


def simd_sse(mm, P, CP, i_target, weights):
    """What ``MonitoringModel.weighted_sse`` returns, from the SIMD kernel."""
    n_pop = CP.shape[0]
    fitness = np.full(n_pop, np.nan)
    status = np.full(n_pop, -1, dtype=np.int64)
    none3, none2 = np.zeros((0, 0, 3)), np.zeros((0, 0))
    _kernel(P, CP, *_inputs(mm), mm.n_sub, np.ascontiguousarray(i_target),
            np.ascontiguousarray(weights), none3, none2, none2, none2, fitness, status, NO_LOOPS)
    return fitness, status


@pytest.fixture(scope="module", params=[(1, "paper"), (2, "paper"), (1, "physical"), (2, "physical")],
                ids=["n_sub=1-paper", "n_sub=2-paper", "n_sub=1-physical", "n_sub=2-physical"])
def case(request):
    n_sub, fault_model = request.param
    mm = MonitoringModel(n_sub=n_sub, kernel="scalar", fault_model=fault_model)
    scalar, well, horizon = conditioning(mm, K)
    P, CP = mm.pack(K)
    return mm, scalar, simd_traces(mm, P, CP), well, horizon, (P, CP)


def test_named_scenarios_and_most_random_candidates_are_well_conditioned(case):
    _, _, _, well, _, _ = case
    assert well[N_RANDOM:N_RANDOM + len(SCENARIOS)].all()
    assert well[:N_RANDOM].sum() >= MIN_WELL


def test_status_agrees(case):
    _, scalar, simd, _, _, _ = case
    np.testing.assert_array_equal(simd["status"], scalar.status)


def test_traces_agree_to_round_off(case):
    _, scalar, simd, well, horizon, _ = case
    assert_traces_agree(simd, scalar, well, horizon)


def test_weighted_sse_agrees(case):
    mm, scalar, _, well, _, (P, CP) = case
    rng = np.random.default_rng(5)
    i_target = scalar.i_abc[N_RANDOM] + 0.05 * rng.standard_normal(scalar.i_abc.shape[1:])
    weights = rng.uniform(0.5, 2.0, size=i_target.shape)
    f_scalar, s_scalar = mm.weighted_sse(K, i_target, weights)
    f_simd, s_simd = simd_sse(mm, P, CP, i_target, weights)
    np.testing.assert_array_equal(s_simd, s_scalar)
    diverged = s_scalar == STATUS_DIVERGED
    assert np.all(np.isinf(f_simd[diverged])) and np.all(np.isfinite(f_simd[~diverged]))
    np.testing.assert_allclose(f_simd[well], f_scalar[well], rtol=TOL)


def test_without_a_target_the_fitness_is_zero_or_inf(case):
    _, scalar, simd, _, _, _ = case
    diverged = scalar.status == STATUS_DIVERGED
    assert np.all(simd["fitness"][~diverged] == 0.0)
    assert np.all(np.isinf(simd["fitness"][diverged]))


@pytest.mark.parametrize("fault_model", ["paper", "physical"])
@pytest.mark.parametrize("n_pop", [1, LANES - 1, LANES + 1, 2 * LANES + 3])
def test_populations_that_do_not_fill_the_last_block(n_pop, fault_model):
    mm = MonitoringModel(kernel="scalar", fault_model=fault_model)
    k = np.resize(np.array(list(SCENARIOS.values())), (n_pop, 8))   # well conditioned
    scalar = mm.simulate_population(k)
    P, CP = mm.pack(k)
    simd = simd_traces(mm, P, CP)
    np.testing.assert_array_equal(simd["status"], scalar.status)
    for name, ref in traces(scalar).items():
        np.testing.assert_allclose(simd[name], ref, rtol=TOL, atol=TOL, err_msg=name)


def test_empty_population():
    mm = MonitoringModel(kernel="scalar")
    P, CP = pack_population(mm.params, np.zeros((0, 8)))
    r = simd_traces(mm, P, CP)
    assert r["status"].shape == (0,) and r["fitness"].shape == (0,)


@pytest.mark.parametrize("poison", ["unstable_pole", "nan_Kp"])
def test_a_diverging_candidate_is_flagged_and_leaves_its_neighbours_alone(poison):
    mm = MonitoringModel(kernel="scalar")
    k = np.resize(K[N_RANDOM:N_RANDOM + 4], (LANES + 2, 8))         # two blocks
    P, CP = pack_population(mm.params, k, mm.theta0)
    bad = CP.copy()
    j = 2
    if poison == "unstable_pole":
        bad[j, [C_PHI, C_PHI + 6]] = 300.0         # unstable winding step: currents blow up
    else:
        bad[j, C_KP] = np.nan
    rng = np.random.default_rng(1)
    i_target = rng.standard_normal((mm.t.size, 3))
    weights = np.ones((mm.t.size, 3))
    f_good, s_good = simd_sse(mm, P, CP, i_target, weights)
    f_bad, s_bad = simd_sse(mm, P, bad, i_target, weights)
    assert s_bad[j] == STATUS_DIVERGED and np.isinf(f_bad[j])
    others = np.arange(len(k)) != j
    np.testing.assert_array_equal(f_bad[others], f_good[others])
    np.testing.assert_array_equal(s_bad[others], s_good[others])
    assert np.all(s_good == STATUS_OK)
    # the scalar kernel says the same
    tr_bad = simd_traces(mm, P, bad)
    i_scalar = np.zeros((len(k), mm.t.size, 3))
    outs = [np.zeros((len(k), mm.t.size)) for _ in range(3)]
    f_scalar, s_scalar = np.zeros(len(k)), np.zeros(len(k), dtype=np.int64)
    from emaphm.models.monitoring import _kernel as scalar_kernel
    scalar_kernel(P, bad, *_inputs(mm), mm.n_sub, np.zeros((0, 3)), np.zeros((0, 3)),
                  i_scalar, *outs, f_scalar, s_scalar, NO_LOOPS)
    np.testing.assert_array_equal(tr_bad["status"], s_scalar)
    np.testing.assert_allclose(tr_bad["i_abc"][others], i_scalar[others], rtol=TOL, atol=TOL)


def test_kernel_refuses_a_population_packed_for_another_step():
    mm = MonitoringModel(n_sub=2)
    P, CP = pack_population(mm.params, K[:3], n_sub=1)
    with pytest.raises(ValueError, match="another n_sub"):
        simd_traces(mm, P, CP)


def test_runaway_angle_falls_back_to_libm():
    """Past TRIG_LIMIT the kernel uses libm like the scalar kernel: same traces."""
    mm = MonitoringModel(theta0=1.5 * TRIG_LIMIT / 4, kernel="scalar")     # p*theta beyond the limit for p >= 3
    assert mm.params.motor.p * mm.theta0 > TRIG_LIMIT
    k = K[N_RANDOM:N_RANDOM + 3]
    scalar = mm.simulate_population(k)
    P, CP = pack_population(mm.params, k, mm.theta0)
    assert P[P_THETA0] == mm.theta0
    simd = simd_traces(mm, P, CP)
    np.testing.assert_array_equal(simd["status"], scalar.status)
    for name, ref in traces(scalar).items():
        np.testing.assert_allclose(simd[name], ref, rtol=TOL, atol=TOL, err_msg=name)


def test_sincos_within_one_ulp_of_libm():
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.uniform(-50.0, 50.0, 20000), rng.uniform(-TRIG_LIMIT, TRIG_LIMIT, 5000),
                        [0.0, -0.0, 1e-300, math.pi / 4, math.pi / 2, math.pi, -3 * math.pi / 2]])
    for v in x:
        s, c = sincos(v)
        s0, c0 = math.sin(v), math.cos(v)
        assert abs(s - s0) <= np.spacing(abs(s0)) and abs(c - c0) <= 2 * np.spacing(abs(c0)), v
    s, c = sincos(np.nan)
    assert math.isnan(s) and math.isnan(c)
    s, c = sincos(np.inf)
    assert math.isnan(s) and math.isnan(c)


def scalar_fdlibm(mm, P, CP, i_target=None, weights=None):
    """The scalar kernel on the SIMD kernel's sines (its ``fdlibm`` switch)."""
    from emaphm.models.monitoring import _kernel as scalar_kernel

    n_pop, n = CP.shape[0], mm.t.size
    store = i_target is None
    shape = (n_pop, n) if store else (0, 0)
    out_i = np.zeros(shape + (3,))
    th, om, tq = (np.zeros(shape) for _ in range(3))
    fitness = np.zeros(n_pop)
    status = np.zeros(n_pop, dtype=np.int64)
    empty = np.zeros((0, 3))
    scalar_kernel(P, np.ascontiguousarray(CP), *_inputs(mm), mm.n_sub,
                  empty if store else np.ascontiguousarray(i_target),
                  empty if store else np.ascontiguousarray(weights),
                  out_i, th, om, tq, fitness, status, NO_LOOPS, True)
    return {"i_abc": out_i, "theta_m": th, "omega_m": om, "torque": tq, "status": status,
            "fitness": fitness}


def test_one_step_the_scalar_kernel_on_the_same_sines_gives_the_simd_bits(case):
    """Both kernels run the one step of emaphm.models.step: on fdlibm's sines the scalar
    kernel gives the SIMD kernel's results bit for bit, for every candidate, the
    ill-conditioned ones included (an ulp of difference would grow there)."""
    mm, _, simd, _, _, (P, CP) = case
    same = scalar_fdlibm(mm, P, CP)
    for name in ("i_abc", "theta_m", "omega_m", "torque", "status"):
        np.testing.assert_array_equal(same[name], simd[name], err_msg=name)
    target = simd["i_abc"][N_RANDOM]          # the nominal scenario's currents as a target
    w = np.full_like(target, 1e-4)
    f_simd, s_simd = simd_sse(mm, P, CP, target, w)
    same = scalar_fdlibm(mm, P, CP, target, w)
    np.testing.assert_array_equal(same["fitness"], f_simd)
    np.testing.assert_array_equal(same["status"], s_simd)
