"""Eq. 4 fitness and the batch objective :class:`emaphm.fitness.Eq4Objective`.

Layers: the weights and the sum of Eq. 4 by hand on tiny arrays; the objective against
a by-hand computation from the monitoring model's own traces; its minimum at the true
``k`` of a noise-free monitoring-model trace (where it is exactly zero); the
measured-trace plumbing (resampling onto the model grid, a trace that does not start at
angle 0 or time 0, the load torque from the metadata); the bookkeeping (stats) and misuse.
"""

from __future__ import annotations

import numpy as np
import pytest
from support import mm_gain_low  # noqa: F401  (a fixture)

from emaphm.faults import SCENARIOS
from emaphm.fitness import FITNESS_MODES, Eq4Objective, eq4_weights, equivalent_current
from emaphm.models.monitoring import STATUS_DIVERGED, MonitoringModel
from emaphm.profiles import Constant, Profile, diagnostic
from emaphm.simulate import simulate
from emaphm.traces import Trace, TraceError, resample

T_S = 1.25e-4          # control period of the default preset (8 kHz)
P_POLES = 4            # pole pairs of the default preset


# ----------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def obj_gain_low(mm_gain_low):
    return Eq4Objective.from_trace(mm_gain_low)


@pytest.fixture(scope="module")
def rm_friction_high():
    """Noise-free reference-model trace of friction-high (k1 = 0.75), on the 8 kHz grid."""
    return simulate(scenario="friction-high")


def _scan(k_true, index, values):
    """Population that varies component ``index`` of ``k_true`` over ``values``."""
    K = np.tile(np.asarray(k_true, dtype=float), (len(values), 1))
    K[:, index] = values
    return K


def _rebuild(trace, **changes):
    """A trace with some arrays replaced (the metadata kept unless given)."""
    fields = dict(t=trace.t, theta_ref=trace.theta_ref, theta_m=trace.theta_m,
                  omega_m=trace.omega_m, i_abc=trace.i_abc, torque=trace.torque, meta=trace.meta)
    fields.update(changes)
    return Trace(**fields)


# ----------------------------------------------------------------------------- Eq. 4 by hand
def test_eq4_weights_by_hand():
    # i = t^2 sampled at dT = 0.5: numpy.gradient gives one-sided differences at the ends
    # and central ones inside: [1, 2, 4, 5] per sample, i.e. [2, 4, 8, 10] A/s.
    dT = 0.5
    i = np.array([0.0, 1.0, 4.0, 9.0])
    w = eq4_weights(i, dT)
    expected = dT / (np.array([2.0, 4.0, 8.0, 10.0]) ** 2 + 1.0)
    np.testing.assert_allclose(w, expected, rtol=1e-15)
    np.testing.assert_allclose(w, [0.1, 0.5 / 17, 0.5 / 65, 0.5 / 101], rtol=1e-15)


def test_eq4_weights_are_per_phase_along_time():
    # three phases: a constant (derivative 0 -> weight dT), a ramp of slope 3 A/s, and t^2
    dT = 0.5
    i = np.column_stack([np.full(4, 7.0), 1.5 * np.arange(4), np.array([0.0, 1.0, 4.0, 9.0])])
    w = eq4_weights(i, dT)
    assert w.shape == (4, 3)
    np.testing.assert_allclose(w[:, 0], dT)
    np.testing.assert_allclose(w[:, 1], dT / (3.0 ** 2 + 1.0))
    np.testing.assert_allclose(w[:, 2], eq4_weights(i[:, 2], dT))


def test_eq4_sum_over_samples_and_phases_by_hand():
    # Eq. 4 written out term by term on a 4 x 3 example, against the vectorised form
    dT = 0.5
    meas = np.array([[0.0, 1.0, -1.0], [1.0, 0.5, -1.5], [4.0, -2.0, -2.0], [9.0, -4.0, -5.0]])
    mm = meas + np.array([[0.1, 0.0, -0.1], [0.2, 0.1, -0.3], [0.0, 0.0, 0.0], [-0.5, 0.2, 0.3]])
    total = 0.0
    for j in range(3):
        col = meas[:, j]
        for n in range(4):
            lo, hi = max(n - 1, 0), min(n + 1, 3)
            dIdT = (col[hi] - col[lo]) / (hi - lo) / dT
            total += (mm[n, j] - meas[n, j]) ** 2 / (dIdT ** 2 + 1.0) * dT
    assert np.sum(eq4_weights(meas, dT) * (mm - meas) ** 2) == pytest.approx(total, rel=1e-14)


def test_equivalent_current_of_balanced_phases_is_the_amplitude():
    theta = np.linspace(0.0, 4 * np.pi, 97)
    amp = 3.7
    i_abc = amp * np.column_stack([np.cos(theta), np.cos(theta - 2 * np.pi / 3),
                                   np.cos(theta + 2 * np.pi / 3)])
    np.testing.assert_allclose(equivalent_current(i_abc), amp, rtol=1e-12)
    # and a single sample (shape (3,) -> scalar), e.g. i_a = 2, i_b = i_c = -1
    assert float(equivalent_current([2.0, -1.0, -1.0])) == pytest.approx(2.0)


# ----------------------------------------------------------------------------- the objective
def test_objective_equals_by_hand_from_population_traces(mm_gain_low, obj_gain_low):
    obj = obj_gain_low
    rng = np.random.default_rng(7)
    K = np.vstack([SCENARIOS["gain-low"], SCENARIOS["nominal"], rng.random((5, 8))])
    pop = obj.model.simulate_population(K)
    assert not (pop.status == STATUS_DIVERGED).any()      # tripped drives (status 2) count
    # the weights and the target by hand from the measured trace (already on the model grid)
    np.testing.assert_array_equal(obj.target, mm_gain_low.i_abc)
    w = T_S / ((np.gradient(mm_gain_low.i_abc, axis=0) / T_S) ** 2 + 1.0)
    np.testing.assert_allclose(obj.weights, w, rtol=1e-14)
    by_hand = np.sum(w[None] * (pop.i_abc - mm_gain_low.i_abc[None]) ** 2, axis=(1, 2))
    np.testing.assert_allclose(obj(K), by_hand, rtol=1e-9, atol=1e-300)


def test_objective_zero_at_truth_and_larger_away(obj_gain_low):
    k_true = SCENARIOS["gain-low"]
    f_true = obj_gain_low(k_true[None, :])
    assert f_true.shape == (1,)
    assert f_true[0] < 1e-20          # same model, same grid, no noise: zero to round-off
    rng = np.random.default_rng(0)
    away = np.clip(k_true + rng.normal(0.0, 0.1, (8, 8)), 0.0, 1.0)
    assert np.all(obj_gain_low(away) > 1e3 * max(f_true[0], 1e-30))
    assert obj_gain_low(SCENARIOS["nominal"][None, :])[0] > 1e-5


def test_objective_scan_has_its_minimum_at_the_truth(obj_gain_low):
    values = np.linspace(0.0, 1.0, 21)                 # 0.25 is values[5]
    f = obj_gain_low(_scan(SCENARIOS["gain-low"], 7, values))
    assert int(np.argmin(f)) == 5
    assert np.all(np.diff(f[:6]) < 0) and np.all(np.diff(f[5:]) > 0)   # unimodal in k8


def test_objective_accepts_a_single_vector_and_returns_one_value(obj_gain_low):
    f1 = obj_gain_low(SCENARIOS["nominal"])
    f2 = obj_gain_low(SCENARIOS["nominal"][None, :])
    assert f1.shape == (1,) and f1[0] == f2[0]


def test_population_order_does_not_matter(obj_gain_low):
    rng = np.random.default_rng(3)
    K = rng.random((6, 8))
    perm = rng.permutation(6)
    np.testing.assert_array_equal(obj_gain_low(K)[perm], obj_gain_low(K[perm]))


def test_the_objective_holds_no_state_a_call_changes(mm_gain_low):
    """What a search evaluated is counted by the search (emaphm.problem.SearchView), not by
    the objective: calling it changes nothing in it."""
    import dataclasses

    obj = Eq4Objective.from_trace(mm_gain_low)
    before = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
    first = obj(np.tile(SCENARIOS["nominal"], (5, 1)))
    obj(np.tile(SCENARIOS["gain-high"], (3, 1)))
    np.testing.assert_array_equal(obj(np.tile(SCENARIOS["nominal"], (5, 1))), first)
    for name, value in before.items():
        assert getattr(obj, name) is value, name
    assert not hasattr(obj, "stats")


def test_model_replays_the_trace_command(mm_gain_low, obj_gain_low):
    m = obj_gain_low.model
    assert isinstance(m, MonitoringModel)
    assert m.t.size == mm_gain_low.n == obj_gain_low.n_samples
    np.testing.assert_allclose(m.t, np.arange(mm_gain_low.n) * T_S, rtol=0, atol=1e-15)
    pop = m.simulate(SCENARIOS["nominal"])
    np.testing.assert_allclose(pop.theta_ref, mm_gain_low.theta_ref, atol=1e-12)
    assert m.theta0 == 0.0


# ----------------------------------------------------------------------------- measured traces
def test_trace_on_a_finer_grid_gives_the_same_objective(rm_friction_high):
    # 2x finer: every model instant is a sample of the finer trace, so resampling back is
    # exact and the objective is the same
    base = Eq4Objective.from_trace(rm_friction_high)
    fine = resample(rm_friction_high, np.arange(2 * rm_friction_high.n - 1) * (T_S / 2))
    obj = Eq4Objective.from_trace(fine)
    assert obj.n_samples == base.n_samples
    np.testing.assert_allclose(obj.target, base.target, rtol=0, atol=1e-12)
    K = _scan(SCENARIOS["friction-high"], 0, np.linspace(0.5, 1.0, 11))
    np.testing.assert_allclose(obj(K), base(K), rtol=1e-9)


def test_trace_on_another_grid_is_resampled_onto_the_model_grid(rm_friction_high):
    # a 10 kHz acquisition of the same run: the objective lives on the 8 kHz model grid
    # and its minimiser along k1 stays where it was
    rm = rm_friction_high
    acq = resample(rm, np.arange(0.0, rm.t[-1], 1e-4))
    assert acq.n != rm.n
    obj = Eq4Objective.from_trace(acq)
    base = Eq4Objective.from_trace(rm)
    n = obj.n_samples
    assert n == int(np.floor(acq.t[-1] / T_S + 1e-9)) + 1
    np.testing.assert_allclose(obj.model.t, np.arange(n) * T_S, atol=1e-15)
    assert obj.target.shape == obj.weights.shape == (n, 3)
    # the resampled target follows the original currents (linear interpolation twice)
    i_peak = np.abs(rm.i_abc).max()
    assert np.abs(obj.target - base.target[:n]).max() < 0.05 * i_peak
    values = np.linspace(0.6, 0.9, 31)                 # step 0.01, 0.75 is values[15]
    K = _scan(SCENARIOS["friction-high"], 0, values)
    i_obj, i_base = int(np.argmin(obj(K))), int(np.argmin(base(K)))
    assert abs(i_obj - i_base) <= 1
    # (the minimiser itself sits above the true 0.75 on a plant trace: the plant's Stribeck
    # friction reads as more Coulomb friction to the monitoring model; test_models pins it)


def test_trace_starting_at_another_angle_is_replayed_from_that_angle(mm_gain_low):
    # a quarter turn is a whole number of electrical periods (p = 4), so the currents of
    # the shifted trace are still the physical ones: the objective stays zero at the truth
    # only if the model starts from the trace's first angle (theta0)
    shift = 2 * np.pi / P_POLES
    tr = _rebuild(mm_gain_low, theta_ref=mm_gain_low.theta_ref + shift,
                  theta_m=mm_gain_low.theta_m + shift)
    obj = Eq4Objective.from_trace(tr)
    assert obj.model.theta0 == pytest.approx(shift, abs=1e-15)
    pop = obj.model.simulate(SCENARIOS["gain-low"])
    assert pop.theta_m[0, 0] == pytest.approx(shift, abs=1e-15)
    assert pop.theta_ref[0] == pytest.approx(shift, abs=1e-12)
    np.testing.assert_allclose(pop.theta_m[0], tr.theta_m, atol=1e-9)
    assert obj(SCENARIOS["gain-low"])[0] < 1e-20
    assert obj(SCENARIOS["nominal"])[0] > 1e-5


def test_trace_starting_at_an_arbitrary_angle(diag_profile, nominal_params):
    # a trace recorded from 1 rad (not a multiple of an electrical period)
    theta0 = 1.0
    profile = Profile(duration=diag_profile.duration,
                      command=diag_profile.command + (Constant(theta0),), name="shifted")
    k = SCENARIOS["gain-low"]
    r = MonitoringModel(nominal_params, profile, theta0=theta0).simulate(k)
    tr = Trace(t=r.t, theta_ref=r.theta_ref, theta_m=r.theta_m[0], omega_m=r.omega_m[0],
               i_abc=r.i_abc[0], meta={"k": k.tolist()})
    obj = Eq4Objective.from_trace(tr)
    assert obj.model.theta0 == pytest.approx(theta0)
    assert obj.model.simulate(k).theta_m[0, 0] == pytest.approx(theta0)
    assert obj(k)[0] < 1e-20
    f = obj(_scan(k, 7, np.linspace(0.0, 1.0, 21)))
    assert int(np.argmin(f)) == 5
    # the same trace replayed from angle 0 would not match at all
    wrong = Eq4Objective(MonitoringModel(nominal_params, obj.model.profile), obj.target,
                         obj.weights)
    assert wrong(k)[0] > 1e-6


def test_trace_starting_at_a_later_time(mm_gain_low, obj_gain_low):
    tr = _rebuild(mm_gain_low, t=mm_gain_low.t + 12.5)
    obj = Eq4Objective.from_trace(tr)
    assert obj.n_samples == obj_gain_low.n_samples
    np.testing.assert_allclose(obj.model.t, obj_gain_low.model.t, atol=1e-15)
    K = _scan(SCENARIOS["gain-low"], 7, np.linspace(0.0, 1.0, 5))
    np.testing.assert_allclose(obj(K), obj_gain_low(K), rtol=1e-6, atol=1e-12)


def test_load_torque_comes_from_the_trace_metadata(nominal_params):
    # a simulated trace under a constant load: the objective replays that load
    prof = diagnostic(load_torque=0.5)
    tr = simulate(scenario="gain-low", model="monitoring", profile=prof)
    obj = Eq4Objective.from_trace(tr)
    assert obj(SCENARIOS["gain-low"])[0] < 1e-20
    # without the metadata (a bench trace) the load is zero and the truth no longer fits
    bare = _rebuild(tr, meta={})
    assert Eq4Objective.from_trace(bare)(SCENARIOS["gain-low"])[0] > 1e-6
    # ... unless the load is given explicitly
    n = obj.n_samples
    given = Eq4Objective.from_trace(bare, load_torque=np.full(n, 0.5))
    assert given(SCENARIOS["gain-low"])[0] < 1e-20
    with pytest.raises(ValueError, match="load_torque must have shape"):
        Eq4Objective.from_trace(bare, load_torque=np.zeros(n - 1))


# ----------------------------------------------------------------------------- equivalent mode
def test_equivalent_mode_is_minimal_at_the_truth(mm_gain_low):
    obj = Eq4Objective.from_trace(mm_gain_low, mode="equivalent")
    assert obj.mode == "equivalent"
    assert obj.target.shape == obj.weights.shape == (mm_gain_low.n, 1)
    np.testing.assert_allclose(obj.target[:, 0], equivalent_current(mm_gain_low.i_abc))
    values = np.linspace(0.0, 1.0, 21)
    f = obj(_scan(SCENARIOS["gain-low"], 7, values))
    assert f.shape == (21,)
    assert int(np.argmin(f)) == 5 and f[5] < 1e-20
    assert np.all(f[np.arange(21) != 5] > 1e-7)


def test_equivalent_mode_by_hand(mm_gain_low):
    obj = Eq4Objective.from_trace(mm_gain_low, mode="equivalent")
    K = np.vstack([SCENARIOS["nominal"], SCENARIOS["gain-high"]])
    pop = obj.model.simulate_population(K)
    meas = equivalent_current(mm_gain_low.i_abc)
    w = eq4_weights(meas, T_S)
    by_hand = np.sum(w[None] * (equivalent_current(pop.i_abc) - meas[None]) ** 2, axis=1)
    np.testing.assert_allclose(obj(K), by_hand, rtol=1e-12)


def test_a_short_circuit_is_told_apart_from_the_same_short_on_another_phase():
    # the per-phase weighting of Eq. 4 (and the equivalent current too) separates a short
    # on phase A from the same short on phase B or C
    tr = simulate(scenario="short-circuit-high", model="monitoring")
    k_a = SCENARIOS["short-circuit-high"]
    k_b, k_c = k_a.copy(), k_a.copy()
    k_b[2], k_b[3] = 0.0, 0.75
    k_c[2], k_c[4] = 0.0, 0.75
    K = np.vstack([k_a, k_b, k_c])
    for mode in FITNESS_MODES:
        f = Eq4Objective.from_trace(tr, mode=mode)(K)
        assert f[0] < 1e-20, mode
        assert np.all(f[1:] > 1e-5), mode


# ----------------------------------------------------------------------------- misuse
def test_unknown_mode_raises(mm_gain_low):
    assert FITNESS_MODES == ("phases", "equivalent")
    with pytest.raises(ValueError, match="unknown fitness mode 'current'"):
        Eq4Objective.from_trace(mm_gain_low, mode="current")


def test_too_short_trace_raises(mm_gain_low):
    # a valid trace (>= 100 samples) on a fine grid that covers fewer than 16 control periods
    n = 150
    t = np.arange(n) * 1e-5
    tr = Trace(t=t, theta_ref=np.zeros(n), theta_m=np.zeros(n), omega_m=np.zeros(n),
               i_abc=np.zeros((n, 3)))
    with pytest.raises(TraceError, match="fewer than 16 control periods"):
        Eq4Objective.from_trace(tr)


def test_invalid_trace_raises(mm_gain_low):
    i = np.array(mm_gain_low.i_abc)
    i[10, 1] = np.nan
    with pytest.raises(TraceError, match="non-finite"):
        Eq4Objective.from_trace(_rebuild(mm_gain_low, i_abc=i))


def test_noise_floor_is_measured_on_the_recorded_samples():
    """A trace sampled 4x slower than the model grid has the same noise floor (to the
    resampling's effect on the weights), not the near-zero second differences of its
    linear interpolation."""
    from emaphm.simulate import DEFAULT_SENSORS

    full = simulate(scenario="friction-high", sensors=DEFAULT_SENSORS, seed=1)
    cols = {k: v[::4] for k, v in full.columns().items()}
    slow = Trace.from_columns(cols, meta=full.meta)
    f_full = Eq4Objective.from_trace(full).noise_floor()
    f_slow = Eq4Objective.from_trace(slow).noise_floor()
    # measured f_slow / f_full = 0.991 on this seed; an interpolated floor would be near 0.
    # (Seeds 2-5 measure 1.20-1.54: the slower trace's second differences keep some signal.)
    assert f_slow == pytest.approx(f_full, rel=0.05)
    assert f_full > 0


# ----------------------------------------------------------------------------- refusals

def _measured(trace, i_abc, model=None):
    from emaphm.traces import Trace

    meta = {k: v for k, v in trace.meta.items() if k != "model"}
    if model:
        meta["model"] = model
    return Trace(t=trace.t, theta_ref=trace.theta_ref, theta_m=trace.theta_m,
                 omega_m=trace.omega_m, i_abc=i_abc, meta=meta)


@pytest.mark.parametrize("case, words", [
    ("dead", r"phase current i_a is constant \(0.013 A"),
    ("zero", r"phase current i_a is constant \(0 A"),
    ("clipped", "phase current i_c is clipped at"),
    ("noiseless", "carry no measurement noise at all"),
])
def test_undiagnosable_currents_are_refused_with_the_reason(rm_friction_high, case, words):
    from emaphm.fitness import check_diagnosable
    from emaphm.traces import TraceError

    i = np.array(rm_friction_high.i_abc, copy=True)
    if case == "dead":                  # (one dead channel alone fails the star-sum check)
        i[:] = [0.013, -0.01, -0.003]
    elif case == "zero":
        i[:] = 0.0
    elif case == "clipped":
        lim = 0.5 * np.abs(i[:, 2]).max()
        i[:, 2] = np.clip(i[:, 2], -lim, lim)
        i[:, 0] = -(i[:, 1] + i[:, 2])  # a drive with two sensors: i_a from the star sum
    tr = _measured(rm_friction_high, i)
    if case == "noiseless":
        # piecewise-linear, noise-free currents (triangles): a synthetic file
        ph = (rm_friction_high.t[:, None] * np.array([10.0, 7.0, 1.0])) % 1.0
        i = 2.0 * (2.0 * np.abs(2.0 * ph - 1.0) - 1.0)
        i[:, 2] = -(i[:, 0] + i[:, 1])
        tr = _measured(rm_friction_high, i)
    with pytest.raises(TraceError, match=words):
        check_diagnosable(tr)
    with pytest.raises(TraceError, match=words):
        Eq4Objective.from_trace(tr)
    # the untouched recording passes
    check_diagnosable(rm_friction_high)


# ----------------------------------------------------------------------------- metadata
@pytest.mark.parametrize("change, match", [
    (lambda p: p["load"].append({"shape": "Constant", "value": "abc"}),
     r"^trace metadata profile\.load\[0\]\.value: expected a number in N m, got the string 'abc'; "
     r"correct the profile, or delete it"),
    (lambda p: p["command"][0].update(height=1e300), r"profile\.command\[0\]\.height = 1e\+300 rad"),
    (lambda p: p["load"].append({"shape": "Constant", "value": 1000.0}),
     r"load torque reaches 1000 N m, more than 10 times the motor's peak torque \(T_max = 18 N m\)"),
])
def test_a_trace_whose_profile_is_nonsense_is_refused(mm_gain_low, change, match):
    # the load of a trace's profile drives the model: a malformed or absurd one is refused
    # (it was silently dropped, or diagnosed from an infinite fitness)
    import copy

    prof = copy.deepcopy(mm_gain_low.meta["profile"])
    change(prof)
    with pytest.raises(TraceError, match=match):
        Eq4Objective.from_trace(mm_gain_low.with_meta(profile=prof))


def test_a_trace_without_a_profile_has_zero_load(mm_gain_low):
    meta = {k: v for k, v in mm_gain_low.meta.items() if k != "profile"}
    bare = Trace(t=mm_gain_low.t, theta_ref=mm_gain_low.theta_ref, theta_m=mm_gain_low.theta_m,
                 omega_m=mm_gain_low.omega_m, i_abc=mm_gain_low.i_abc, meta=meta)
    obj = Eq4Objective.from_trace(bare)
    assert not np.any(obj.model.profile.load_torque(obj.model.t))
