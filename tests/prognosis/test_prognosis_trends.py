"""Degradation trends, RUL distributions and the degradation simulator.

Known answers on noiseless data (fits, closed-form crossing times), determinism under
an explicit seed, misuse with precise messages, and the statistical claims of the
issue on synthetic k histories (true law + identification-level noise, 0.007 per
component): from mid-life on the 90 % RUL interval holds the true RUL in most
histories, and the median error falls as inspections accumulate. The trend maths
needs no identification, so these run in seconds; the real loop is in
``test_prognosis_e2e.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from emaphm.prognosis.simulator import (DEGRADATION_SCENARIOS, DegradationLaw, DegradationScenario,
                                        degradation_scenario, inspection_times, synthetic_k_history)
from emaphm.prognosis.thresholds import (DEFAULT_FAILURE_THRESHOLDS, INDICATOR_COMPONENT, INDICATORS, FailureThresholds,
                                         indicator_values, parse_threshold)
from emaphm.prognosis.trends import (fit_trend, fit_trends, indicator_series, indicator_state,
                                     predict_rul, prognose, rul_track, select)

T = np.linspace(0.0, 500.0, 8)


# ----------------------------------------------------------------------------- fits
def test_linear_fit_known_answer_and_covariance():
    rng = np.random.default_rng(0)
    y = 0.02 + 4e-4 * T + 0.005 * rng.standard_normal(T.size)
    f = fit_trend(T, y, "linear")
    X = np.column_stack([np.ones_like(T), T - T[-1]])
    beta = np.linalg.lstsq(X, y, rcond=None)[0]
    np.testing.assert_allclose(f.theta, beta, rtol=1e-10)
    s2 = np.sum((y - X @ beta) ** 2) / (T.size - 2)
    np.testing.assert_allclose(f.cov, s2 * np.linalg.inv(X.T @ X), rtol=1e-8)
    assert f.value(T[-1])[0] == pytest.approx(beta[0])      # theta[0] is the level now


@pytest.mark.parametrize("model, truth", [
    ("linear", lambda t: 0.01 + 5e-4 * t),
    ("exponential", lambda t: 0.02 * np.exp(t / 200.0)),
    ("quadratic", lambda t: 0.01 + 1e-4 * t + 1e-6 * t ** 2),
    ("onset", lambda t: 0.01 + 8e-4 * np.maximum(t - 130.0, 0.0)),
])
def test_noiseless_fits_recover_the_law_and_its_crossing(model, truth):
    y = truth(T)
    f = fit_trend(T, y, model)
    grid = np.linspace(0, 900, 50)
    np.testing.assert_allclose(f.value(grid), truth(grid), rtol=1e-6, atol=1e-9)
    thr = 0.6
    t_cross = float(f.crossing_time(thr)[0])
    assert truth(t_cross) == pytest.approx(thr, rel=1e-6)
    assert t_cross > T[-1]


def _exponential_by_trust_region(tau, y):
    """The oracle of the fast exponential fit: scipy's bounded trust-region least squares
    on (alpha, b) from a grid of 21 starting rates, the best of them."""
    from scipy import optimize

    from emaphm.prognosis.shapes import _ALPHA_MIN, SHAPES

    exp = SHAPES["exponential"]

    span = float(tau[-1] - tau[0])
    level = max(float(np.max(np.abs(y))), 1e-6)
    best = None
    for rate in np.linspace(-50.0, 50.0, 21):
        x0 = np.array([min(max(math.log(level), _ALPHA_MIN + 1.0), 2.0), rate / span])
        res = optimize.least_squares(
            lambda th: exp.value(th, tau) - y, x0,
            jac=lambda th: exp.jacobian(th, tau),
            bounds=([_ALPHA_MIN, -60.0 / span], [math.log(10.0), 60.0 / span]),
            method="trf", x_scale=[1.0, 1.0 / span])
        if best is None or res.cost < best.cost:
            best = res
    return best.x, 2.0 * best.cost


def test_the_exponential_fit_finds_the_least_squares_minimum_of_a_trust_region_search():
    """Growing, scattering-at-zero, linear and level series, 3 to 40 inspections: the
    variable-projection fit's residual sum of squares is never above the best of a
    multistart trust-region search's (and equal where both find the same minimum)."""
    from emaphm.prognosis.shapes import SHAPES, _fit_exponential

    rng = np.random.default_rng(20261126)
    for trial in range(80):
        t = np.unique(np.sort(rng.uniform(0.0, 2000.0, int(rng.integers(3, 40)))))
        noise = rng.normal(0.0, 0.007, t.size)
        y = (0.02 * np.exp(t / rng.uniform(100.0, 3000.0)) + noise, noise,
             0.1 + 1e-4 * t + noise, np.abs(0.3 + 10 * noise))[trial % 4]
        tau = t - t[-1]
        theta = _fit_exponential(tau, y)
        rss = float(np.sum((SHAPES["exponential"].value(theta, tau) - y) ** 2))
        ref, ref_rss = _exponential_by_trust_region(tau, y)
        assert rss <= ref_rss * (1 + 1e-7) + 1e-15, (trial, theta, ref)
        if trial % 4 == 0:                     # a clear growth: the same parameters
            np.testing.assert_allclose(theta, ref, rtol=1e-4, atol=1e-6 / (tau[-1] - tau[0]))


def test_the_onset_fit_recovers_the_onset_and_is_the_least_squares_minimum():
    """Known answer: a noise-free hinge at 130 h (between the 2nd and 3rd inspection)
    gives back its level, slope and onset, with the straight line's crossing after it.
    Oracle: on noisy hinges, lines and flat series the fit's residual is never above the
    least of a fine brute-force scan of the onset (and never above the straight line's)."""
    from emaphm.prognosis.shapes import SHAPES, _fit_onset

    f = fit_trend(T, 0.01 + 8e-4 * np.maximum(T - 130.0, 0.0), "onset")
    np.testing.assert_allclose(f.theta, [0.01 + 8e-4 * 370.0, 8e-4, 130.0 - 500.0], rtol=1e-6)
    assert f.crossing_time(0.5)[0] == pytest.approx(130.0 + 0.49 / 8e-4, rel=1e-9)
    assert fit_trend(T, 0.01 + 8e-4 * np.maximum(T - 130.0, 0.0), "linear").rss > 1e-4
    rng = np.random.default_rng(20261127)
    for trial in range(60):
        t = np.unique(np.sort(rng.uniform(0.0, 2000.0, int(rng.integers(5, 30)))))
        noise = rng.normal(0.0, 0.007, t.size)
        onset = rng.uniform(0.0, 1500.0)
        y = (np.abs(2e-4 * np.maximum(t - onset, 0.0) + noise), 0.1 + 1e-4 * t + noise,
             np.abs(noise))[trial % 3]
        tau = t - t[-1]
        theta = _fit_onset(tau, y)
        rss = float(np.sum((SHAPES["onset"].value(theta, tau) - y) ** 2))
        scan = np.linspace(tau[0], tau[-3], 20001)
        X = np.maximum(tau[None, :], scan[:, None])
        best = min(float(np.sum((y - np.polyval(np.polyfit(x, y, 1), x)) ** 2)) for x in X[::40])
        assert rss <= best * (1 + 1e-9) + 1e-15, (trial, theta)
        assert rss <= fit_trend(t, y, "linear").rss * (1 + 1e-9) + 1e-15
        assert tau[0] <= theta[2] <= tau[-3]


def test_an_onset_after_a_healthy_stretch_is_not_read_as_acceleration():
    """A fault that starts growing linearly after a healthy stretch (the indicator at 0,
    scattering, before it): without the onset model the flat inspections bend the fit into
    a convex curve whose median RUL is far too short; with it the median is near the truth."""
    t = np.arange(0.0, 1300.0, 150.0)                       # 9 inspections, onset at 700 h
    rng = np.random.default_rng(3)
    y = np.abs(6e-4 * np.maximum(t - 700.0, 0.0) + rng.normal(0.0, 0.007, t.size))
    true_rul = 700.0 + 0.5 / 6e-4 - t[-1]
    with_onset = predict_rul(t, y, 0.5, seed=0)
    without = predict_rul(t, y, 0.5, seed=0, models=("linear", "exponential", "quadratic"))
    assert with_onset.weights["onset"] > 0.5
    assert abs(with_onset.median - true_rul) < 0.15 * true_rul
    assert without.median < 0.75 * true_rul


def test_crossing_time_edge_cases():
    f = fit_trend(T, 0.5 + 0.0 * T, "linear")
    assert f.crossing_time(0.4)[0] == T[-1]                  # already past: fails now
    assert np.isinf(f.crossing_time(0.6, theta=np.array([[0.5, 0.0]]))[0])   # flat below: never
    f = fit_trend(T, 0.3 - 1e-4 * T, "linear")
    assert np.isinf(f.crossing_time(0.5)[0])                 # improving: never
    q = fit_trend(T, 0.1 + 1e-3 * T - 2e-6 * T ** 2, "quadratic")
    assert np.isinf(q.crossing_time(0.5)[0])                 # peaks at 0.225 below 0.5


def test_model_selection_prefers_the_true_shape():
    rng = np.random.default_rng(1)
    t = np.linspace(0, 900, 10)
    lin = 0.02 + 5e-4 * t + 0.003 * rng.standard_normal(t.size)
    exp_ = 0.01 * np.exp(t / 250.0) + 0.003 * rng.standard_normal(t.size)
    w_lin = select(fit_trends(t, lin, ("linear", "exponential")))
    w_exp = select(fit_trends(t, exp_, ("linear", "exponential")))
    assert w_lin["linear"] > 0.5 and w_exp["exponential"] > 0.99
    assert sum(w_exp.values()) == pytest.approx(1.0)


def test_models_join_once_their_aicc_is_finite():
    t = T[:4]
    assert set(fit_trends(t, 1e-3 * t)) == {"linear", "exponential"}     # quadratic needs 5
    assert set(fit_trends(T[:5], 1e-3 * T[:5])) == {"linear", "exponential", "quadratic", "onset"}


# ----------------------------------------------------------------------------- RUL
def test_rul_of_a_clean_linear_trend():
    y = 1e-3 * T                                            # reaches 0.5 at t = 500 -> RUL 0
    t = T * 0.8                                              # last inspection at 400
    p = predict_rul(t, 1e-3 * t, 0.5, seed=0, sigma_floor=1e-4)
    assert p.median == pytest.approx(100.0, rel=0.02)
    assert p.lo < 100.0 < p.hi and p.hi - p.lo < 20.0
    assert p.p_failed == 0.0 and p.p_reach == 1.0
    p_now = predict_rul(T, y + 0.01, 0.5, seed=0, sigma_floor=1e-4)
    assert p_now.median == 0.0 and p_now.p_failed > 0.5
    later = predict_rul(t, 1e-3 * t, 0.5, seed=0, sigma_floor=1e-4, t_now=450.0)
    assert later.median == pytest.approx(50.0, rel=0.05)


def test_a_wrong_identification_is_left_out():
    """An inspection whose identification landed in a wrong basin (seen in the benchmark:
    Eq. 9 error 70 %) must not bend the trend; the last two inspections always count."""
    t = np.linspace(0, 900, 10)
    rng = np.random.default_rng(4)
    y = 5e-4 * t + 0.003 * rng.standard_normal(t.size)
    clean = predict_rul(t, y, 0.5, seed=0)
    assert clean.excluded == ()
    bad = y.copy()
    bad[5] = -0.06
    p = predict_rul(t, bad, 0.5, seed=0)
    assert p.excluded == (5,)
    assert abs(p.median - clean.median) < 0.1 * clean.median
    assert predict_rul(t, bad, 0.5, seed=0, reject_outliers=False).excluded == ()
    bad[-1] = 0.9                                   # a jump at the end is news, not noise
    assert 9 not in predict_rul(t, bad, 0.5, seed=0).excluded


def test_no_growth_never_reaches():
    rng = np.random.default_rng(2)
    p = predict_rul(T, 0.003 * np.abs(rng.standard_normal(T.size)), 0.5, seed=0)
    assert math.isinf(p.median) and p.p_reach < 0.5
    assert p.to_dict()["rul_median"] is None                 # JSON has no infinity


def test_same_seed_same_rul_and_seed_is_required():
    rng = np.random.default_rng(3)
    y = 0.01 + 8e-4 * T + 0.007 * rng.standard_normal(T.size)
    a = predict_rul(T, y, 0.5, seed=42)
    b = predict_rul(T, y, 0.5, seed=42)
    c = predict_rul(T, y, 0.5, seed=43)
    np.testing.assert_array_equal(a.samples, b.samples)
    assert (a.median, a.lo, a.hi) == (b.median, b.lo, b.hi)
    assert not np.array_equal(a.samples, c.samples)
    with pytest.raises(ValueError, match="explicit seed"):
        predict_rul(T, y, 0.5, seed=None)


@pytest.mark.parametrize("kwargs, match", [
    (dict(t=T[:2], y=T[:2] * 1e-3), "at least 3 inspections"),
    (dict(t=T[::-1], y=T * 1e-3), "strictly increasing"),
    (dict(threshold=-0.1), "positive number"),
    (dict(threshold=float("nan")), "positive number"),
    (dict(selection="best"), "unknown model selection"),
    (dict(models=("cubic",)), "unknown trend model"),
    (dict(level=1.5), "level must be in"),
    (dict(n_samples=10), "n_samples"),
    (dict(t_now=10.0), "before the last inspection"),
    (dict(y=np.r_[T[:-1] * 1e-3, np.nan]), "finite"),
])
def test_predict_rul_misuse(kwargs, match):
    args = dict(t=T, y=T * 1e-3, threshold=0.5)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        predict_rul(args.pop("t"), args.pop("y"), args.pop("threshold"), seed=0, **args)


@given(a=st.floats(0.0, 0.2), b=st.floats(1e-4, 2e-3), thr=st.floats(0.25, 0.9))
def test_property_noiseless_linear_median_is_the_analytic_rul(a, b, thr):
    y = a + b * T
    p = predict_rul(T, y, thr, seed=0, models=("linear",), sigma_floor=1e-6, n_samples=200)
    expect = max((thr - a) / b - T[-1], 0.0)
    assert p.median == pytest.approx(expect, rel=1e-3, abs=1e-3)


def test_prognose_all_indicators_and_subset_independence():
    sc = degradation_scenario("friction-growth")
    t = inspection_times(sc.eol, 8)
    K = synthetic_k_history(sc, t, seed=5)
    full = prognose(t, K, seed=9)
    # every indicator of k; the demagnetization's readings are not in k (none given: no
    # prediction)
    assert set(full.predictions) == set(INDICATOR_COMPONENT)
    assert full.first.indicator == "friction"
    only = prognose(t, K, seed=9, indicators=("friction",))
    np.testing.assert_array_equal(only.predictions["friction"].samples,
                                  full.predictions["friction"].samples)
    back = full.predictions["backlash"]                      # nothing grows there: far or never
    assert back.median > 10 * full.predictions["friction"].hi and math.isinf(back.hi)
    d = full.to_dict()
    assert d["n_inspections"] == 8 and d["predictions"]["friction"]["rul_median"] > 0
    with pytest.raises(ValueError, match="unknown health indicator"):
        prognose(t, K, seed=0, indicators=("wear",))


def test_gain_drift_indicator_keeps_its_sign():
    K = np.tile([0, 0, 0, 0, 0, 0, 0.5, 0.5], (3, 1))
    K[:, 7] = [0.502, 0.49, 0.45]
    np.testing.assert_allclose(indicator_series(K)["gain_drift"], [-0.002, 0.01, 0.05])
    np.testing.assert_allclose(indicator_values(K)["gain_drift"], [0.002, 0.01, 0.05])


# ----------------------------------------------------------------------------- thresholds
def test_thresholds_defaults_updates_and_misuse():
    th = DEFAULT_FAILURE_THRESHOLDS
    assert (th.friction, th.backlash, th.short_circuit, th.eccentricity, th.gain_drift) == \
        (0.5, 0.5, 0.3, 0.5, 0.25)
    assert th.for_indicator("short_circuit_b") == 0.3
    new = th.with_updates(dict([parse_threshold("friction=0.4"), parse_threshold("short-circuit-a=0.2")]))
    assert new.friction == 0.4 and new.short_circuit == 0.2 and th.friction == 0.5
    with pytest.raises(ValueError, match=r"gain_drift must be in \(0, 0.5\]"):
        FailureThresholds(gain_drift=0.6)
    with pytest.raises(ValueError, match="MODE=VALUE"):
        parse_threshold("friction")
    with pytest.raises(ValueError, match="not a number"):
        parse_threshold("friction=high")


# ----------------------------------------------------------------------------- simulator
@pytest.mark.parametrize("kind", ["linear", "exponential", "power"])
def test_law_reaches_its_level_when_told(kind):
    law = DegradationLaw.reaching(kind, 0.4, 800.0, onset=100.0)
    assert float(law.value(800.0)) == pytest.approx(0.4)
    assert law.crossing_time(0.4) == pytest.approx(800.0)
    assert float(law.value(50.0)) == pytest.approx(law.d0)          # before the onset
    assert np.all(np.diff(law.value(np.linspace(100, 900, 20))) > 0)


def test_scenarios_and_synthetic_histories():
    for name, sc in DEGRADATION_SCENARIOS.items():
        assert sc.eol == pytest.approx(1000.0), name
    g = degradation_scenario("gain-drift")
    assert g.k_at(1000.0)[7] == pytest.approx(0.25)                  # drifts downward
    t = inspection_times(g.eol, 6)
    a = synthetic_k_history(g, t, seed=1)
    np.testing.assert_array_equal(a, synthetic_k_history(g, t, seed=1))
    assert not np.array_equal(a, synthetic_k_history(g, t, seed=2))
    assert np.all((a >= 0) & (a <= 1))
    assert np.abs(a - g.k_at(t)).max() < 0.05
    with pytest.raises(ValueError, match="leaves \\[0, 1\\]"):
        DegradationScenario("gain_drift", DegradationLaw("linear", 1e-3), direction=-1).k_at(600.0)
    with pytest.raises(ValueError, match="unknown degradation scenario"):
        degradation_scenario("rust")
    with pytest.raises(ValueError, match="explicit seed"):
        synthetic_k_history(g, t, seed=None)
    with pytest.raises(ValueError, match="unknown degradation law"):
        DegradationLaw("sigmoid", 1.0)


# ----------------------------------------------------------------------------- the claims
N_HISTORIES = 40
N_INSPECTIONS = 10


def _tracks(name):
    sc = degradation_scenario(name)
    t = inspection_times(sc.eol, N_INSPECTIONS)
    out = []
    for h in range(N_HISTORIES):
        y = indicator_series(synthetic_k_history(sc, t, seed=1000 + h))[sc.indicator]
        out.append(rul_track(t, y, sc.threshold, seed=h, n_samples=1000))
    return sc, t, out


@pytest.mark.parametrize("name", ["friction-growth", "short-circuit-growth", "gain-drift"])
def test_interval_holds_true_rul_from_midlife_and_error_falls(name):
    sc, t, tracks = _tracks(name)
    times = tracks[0].times
    late = times >= 0.5 * sc.eol
    rul_true = sc.eol - times
    inside = np.array([(tr.lo <= rul_true) & (rul_true <= tr.hi) for tr in tracks])
    cover = inside[:, late].mean(axis=0)
    # nominal 90 %: every mid-life-on inspection covers in >= 70 % of the histories, and
    # >= 80 % over all of them together (binomial sd about 0.05 and 0.02 at 40 histories)
    assert cover.min() >= 0.7, cover
    assert inside[:, late].mean() >= 0.8, cover
    err = np.median(np.abs(np.array([tr.median for tr in tracks]) - rul_true), axis=0)
    mid = err[late]
    assert err[-1] < 0.25 * err[0], err                      # falls over the life
    assert mid[-1] < 0.75 * mid[0], err                      # and from mid-life to the end
    assert np.all(np.diff(mid) <= 0.15 * mid[0]), err        # never climbing much on the way


def test_the_rul_figure_says_no_growth_and_does_not_stretch_for_it():
    from emaphm.prognosis.plots import interesting_indicators, plot_prognosis
    from emaphm.prognosis.trends import prognose as _prognose

    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 500.0, 8)
    K = np.tile([0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5], (t.size, 1))
    K[:, 0] = 0.0008 * t + rng.normal(0, 0.005, t.size)          # friction grows
    K[:, 1] = 0.01 + rng.normal(0, 0.003, t.size)                 # backlash does not
    prog = _prognose(t, K, seed=0)
    span = t[-1] - t[0]
    assert not prog.predictions["friction"].no_growth(span)
    assert prog.predictions["backlash"].no_growth(span)
    assert "backlash" not in interesting_indicators(prog)
    assert interesting_indicators(prog)[0] == "friction"
    fig = plot_prognosis(prog, indicators=["friction", "backlash"])
    grow, flat = fig.axes
    assert flat.get_title() == "backlash: no growth"
    assert any("no growth" in x.get_text() for x in flat.texts)
    assert flat.get_xlim()[1] <= t[-1] + 0.6 * span               # not stretched to 1e5 h
    assert not [ln for ln in flat.lines if ln.get_marker() == "D"]  # no median drawn
    assert grow.get_title().startswith("friction: RUL median")


def test_a_flat_history_names_no_first_failure():
    """A healthy k that only scatters about zero: some indicator's trend (an exponential
    through the scatter) still crosses its distant threshold at a finite median (gain
    drift after 1977 h here), which is no prediction of a failure. ``first`` keeps only
    the indicators past their threshold or rising beyond two standard errors, so it is
    None, and a growing fault is still first (test above)."""
    from emaphm.faults import K_NOMINAL

    rng = np.random.default_rng(0)
    t = np.array([0.0, 100.0, 200.0, 300.0, 400.0, 500.0])
    K = np.tile(K_NOMINAL, (t.size, 1)) + np.abs(rng.normal(0, 0.003, (t.size, 8))) * (np.arange(8) != 6)
    prog = prognose(t, K, seed=1)
    naive = min(prog.predictions.values(), key=lambda p: (p.median, p.lo))
    assert math.isfinite(naive.median)                  # the case the rule is for
    assert prog.first is None


# ----------------------------------------------------------------- model discrepancy

def test_a_relative_discrepancy_moves_the_threshold_by_its_normal_quantiles():
    """Known answer: a noise-free linear indicator 0.001 t reaches 0.5 at 500 h; read with
    a relative discrepancy d, the true crossing is at 500 (1 + delta), delta ~ N(0, d), so
    the 90 % RUL interval from t = 200 h is 500 (1 -+ 1.645 d) - 200."""
    from emaphm.prognosis.trends import predict_rul

    t = np.linspace(0.0, 200.0, 6)
    y = 0.001 * t
    bare = predict_rul(t, y, 0.5, seed=1, sigma_floor=1e-7, n_samples=20000)
    wide = predict_rul(t, y, 0.5, seed=1, sigma_floor=1e-7, n_samples=20000, discrepancy=0.05)
    assert bare.median == pytest.approx(300.0, abs=0.5) and bare.hi - bare.lo < 1.0
    assert wide.lo == pytest.approx(500 * (1 - 1.645 * 0.05) - 200, abs=2.0)
    assert wide.hi == pytest.approx(500 * (1 + 1.645 * 0.05) - 200, abs=2.0)
    assert wide.median == pytest.approx(300.0, abs=1.5)
    assert wide.discrepancy == 0.05 and wide.to_dict()["discrepancy"] == 0.05
    # zero discrepancy draws nothing more: the same draws as before it existed
    again = predict_rul(t, y, 0.5, seed=1, sigma_floor=1e-7, n_samples=20000, discrepancy=0.0)
    np.testing.assert_array_equal(again.samples, bare.samples)
    for bad in (-0.1, 1.0, float("nan"), True, "0.05"):
        with pytest.raises(ValueError, match="discrepancy"):
            predict_rul(t, y, 0.5, seed=1, discrepancy=bad)


def test_prognose_carries_each_indicators_measured_discrepancy():
    from emaphm.faults import K_NOMINAL
    from emaphm.prognosis import prognose
    from emaphm.prognosis.trends import MODEL_DISCREPANCY

    times = np.linspace(0.0, 600.0, 7)
    K = np.tile(K_NOMINAL, (times.size, 1))
    K[:, 0] = 0.0006 * times + np.array([0.002, -0.001, 0.0, 0.001, -0.002, 0.001, 0.0])
    default = prognose(times, K, seed=3, indicators=("friction",))
    none = prognose(times, K, seed=3, indicators=("friction",), discrepancy={})
    p, q = default.predictions["friction"], none.predictions["friction"]
    assert p.discrepancy == MODEL_DISCREPANCY["friction"] > 0 and q.discrepancy == 0.0
    assert p.hi - p.lo > q.hi - q.lo                    # the offset the scatter cannot see
    assert p.lo <= q.median <= p.hi
    assert set(MODEL_DISCREPANCY) == set(INDICATORS)   # every indicator has a measured value
    with pytest.raises(ValueError, match="unknown health indicator"):
        prognose(times, K, seed=3, discrepancy={"bearing": 0.1})


# ----------------------------------------------------------------- the range of k

def _growing_friction(t: np.ndarray) -> np.ndarray:
    """A k history whose friction grows by 8e-4 per hour (0.4 at 500 h) over a healthy rest
    that scatters about zero (clipped at 0, as identifications are)."""
    from emaphm.faults import K_NOMINAL

    rng = np.random.default_rng(5)
    K = np.tile(K_NOMINAL, (t.size, 1))
    K[:, 0] = 8e-4 * t + rng.normal(0, 0.003, t.size)
    K[:, 1:6] = np.abs(rng.normal(0, 0.003, (t.size, 5)))
    return np.clip(K, 0.0, 1.0)


def test_a_trend_read_beyond_k_1_says_it_is_extrapolated():
    """k lies in [0, 1] by definition; a trend does not know it. Read at 1500 h the friction
    trend is at about 1.2, a k that cannot exist: the prediction says so, with the value.
    At the last inspection nothing is extrapolated, and the healthy components, whose
    trends dip below 0 by their scatter, are not flagged either."""
    from emaphm.prognosis.trends import INDICATOR_BOUNDS

    K = _growing_friction(T)
    now = prognose(T, K, seed=0)
    assert {n: p.extrapolated for n, p in now.predictions.items()} == \
        dict.fromkeys(INDICATOR_COMPONENT, "")
    assert now.predictions["friction"].to_dict()["extrapolated"] is None
    late = prognose(T, K, seed=0, t_now=1500.0).predictions
    f = late["friction"]
    assert f.current > 1.1 and f.bounds == INDICATOR_BOUNDS["friction"] == (0.0, 1.0)
    assert f.extrapolated == f"extrapolated beyond k = 1: the trend is at {f.current:.3g} at 1500"
    assert f.to_dict()["extrapolated"] == f.extrapolated and f.to_dict()["bounds"] == [0.0, 1.0]
    assert [n for n, p in late.items() if p.extrapolated] == ["friction"]
    assert INDICATOR_BOUNDS["gain_drift"] == (-0.5, 0.5)


def test_draws_whose_threshold_the_discrepancy_moves_past_k_1_are_extrapolated():
    """A threshold of 0.98 moved by a 5 % model discrepancy lies beyond k = 1 in a third of
    the draws (P(delta > 0.0204 / 0.98) = P(z > 0.417) = 0.34): their failure needs a k the
    identification cannot read. Without the discrepancy nothing is extrapolated."""
    y = 0.002 * T
    bare = predict_rul(T, y, 0.98, seed=2, bounds=(0.0, 1.0), n_samples=20000)
    assert bare.extrapolated == ""
    wide = predict_rul(T, y, 0.98, seed=2, bounds=(0.0, 1.0), n_samples=20000, discrepancy=0.05)
    head, _, share = wide.extrapolated.partition(": ")
    assert head == "extrapolated beyond 1"                # a free indicator: its bound
    # 33.8 % expected, 0.33 % the binomial error of 20,000 draws; the mix of models of a
    # noise-free line rests on residuals of rounding size, so the draws are not pinned
    assert abs(int(share.split("%")[0]) - 33.8) <= 1.5 and "% of the draws" in share
    k = predict_rul(T, y, 0.98, seed=2, bounds=(0.0, 1.0), n_samples=20000, discrepancy=0.05,
                    indicator="friction")
    assert k.extrapolated.startswith(f"extrapolated beyond k = 1: {share.split('%')[0]}% of")


def test_beyond_names_the_bound_where_the_whole_cone_leaves_it():
    """Known answer: a noise-free 0.002 t (sigma floor 1e-4) is 1 at 500 h and -0.2 at
    -100 h; the cone is too narrow to hold either bound there, and holds both near them.
    (The straight line alone: the onset model stays flat before its onset, 0 at -20 h.)"""
    p = predict_rul(T, 0.002 * T, 0.5, seed=0, bounds=(0.0, 1.0), indicator="backlash",
                    sigma_floor=1e-4, models=("linear",))
    assert p.beyond([0.0, 250.0, 499.0]) == ""
    assert p.beyond([250.0, 520.0]) == "extrapolated beyond k = 1"
    assert p.beyond([-20.0, 250.0]) == "extrapolated below k = 0"
    g = predict_rul(T, 0.002 * T, 0.25, seed=0, bounds=(-0.5, 0.5), indicator="gain_drift",
                    sigma_floor=1e-4)
    assert g.beyond(300.0) == "extrapolated beyond k8 = 0 or 1"
    assert predict_rul(T, 0.002 * T, 0.5, seed=0).beyond(1e9) == ""     # unbounded
    assert predict_rul(T, 0.002 * T, 0.5, seed=0, bounds=(0, 1)).beyond(1e9) == "extrapolated beyond 1"


@pytest.mark.parametrize("bounds", [(1.0, 0.0), (0.0, 0.4), (0.0,), "01", (0.0, "a")])
def test_bounds_must_hold_the_threshold(bounds):
    with pytest.raises(ValueError, match="bounds"):
        predict_rul(T, 8e-4 * T, 0.5, seed=0, bounds=bounds)


def test_the_rul_figure_says_when_its_trend_leaves_k_1():
    from emaphm.prognosis.plots import plot_prognosis

    K = _growing_friction(T)
    notes = lambda fig: [x.get_text() for ax in fig.axes for x in ax.texts]   # noqa: E731
    assert "extrapolated beyond k = 1" in notes(plot_prognosis(prognose(T, K, seed=0, t_now=1500.0),
                                                              indicators=["friction"]))
    assert notes(plot_prognosis(prognose(T, K, seed=0), indicators=["friction"])) == []
    # drawn far enough, the median trend itself passes k = 1
    assert "extrapolated beyond k = 1" in notes(plot_prognosis(prognose(T, K, seed=0),
                                                              indicators=["friction"], horizon=1200))


# ----------------------------------------------------------------------------- issue 37: long
def _with_outliers(rng, n):
    t = np.cumsum(rng.uniform(1.0, 50.0, n))
    y = 0.05 + rng.uniform(0.0, 0.2) * t / t[-1] + rng.normal(0.0, 0.004, n)
    if rng.random() < 0.5:
        y += rng.uniform(0.0, 0.05) * (t / t[-1]) ** 2
    idx = rng.choice(n - 2, size=min(int(rng.integers(0, 4)), n - 2), replace=False)
    y[idx] += rng.choice([-1.0, 1.0], size=idx.size) * rng.uniform(0.02, 0.2, idx.size)
    return t, y


def test_the_leave_one_out_screen_leaves_out_what_a_refit_per_inspection_does():
    """The screen's closed form (residual over one minus leverage) against its reference,
    a fit without each inspection, on 300 seeded histories of 6 to 80 inspections with up
    to three wrong identifications each."""
    from emaphm.prognosis.fits import _inliers, _inliers_refit

    rng = np.random.default_rng(37)
    left_out = 0
    for _ in range(300):
        t, y = _with_outliers(rng, int(rng.integers(6, 80)))
        fits = fit_trends(t, y, sigma_floor=0.003)
        fast = _inliers(t, y, fits, 0.003)
        assert np.array_equal(fast, _inliers_refit(t, y, fits, 0.003))
        left_out += int((~fast).sum())
    assert left_out > 100


def test_the_onset_profile_is_the_least_squares_of_its_regressor_matrix():
    """The closed form from cumulative sums against the regressor matrix max(tau, c) of
    every onset, (m, n), as it was computed (1.6 GB at 10,000 inspections)."""
    from emaphm.prognosis.shapes import _onset_profile

    rng = np.random.default_rng(7)
    for _ in range(200):
        n = int(rng.integers(3, 300))
        tau = np.cumsum(rng.uniform(0.1, 1e3, n))
        tau -= tau[-1]
        y = 0.01 * rng.normal(size=n) + 1e-4 * np.maximum(tau, tau[n // 2])
        c = np.r_[tau[:max(n - 2, 1)], rng.uniform(tau[0], tau[max(n - 3, 0)], 20)]
        X = np.maximum(tau[None, :], c[:, None])
        dx, dy = X - X.mean(axis=1)[:, None], y - y.mean()
        sxx, sxy = np.einsum("ij,ij->i", dx, dx), dx @ dy
        b = sxy / sxx
        a, rss = y.mean() - b * X.mean(axis=1), np.maximum(dy @ dy - b * sxy, 0.0)
        got = _onset_profile(tau, y, c)
        np.testing.assert_allclose(got[2], rss, rtol=1e-7, atol=1e-12 * float(dy @ dy))
        np.testing.assert_allclose(got[1] * np.ptp(tau), b * np.ptp(tau), rtol=1e-7,
                                   atol=1e-12)
        np.testing.assert_allclose(got[0], a, rtol=1e-7, atol=1e-12)


def test_a_history_of_ten_thousand_inspections_is_prognosed_whole():
    """A year of daily checks, and more: 10,000 inspections, 1 in 200 a wrong basin. Every
    indicator is predicted, the wrong basins are left out, and friction is found growing
    towards its threshold (it took 3 GB and minutes, quadratic in the inspections;
    the time and memory are in BENCHMARKS.md, bench_long_history.py)."""
    rng = np.random.default_rng(10_000)
    n = 10_000
    t = 24.0 * np.arange(n)
    K = np.zeros((n, 8))
    K[:, 6:] = 0.5
    K[:, 0] = 0.05 + 0.3 * np.arange(n) / n
    K += rng.normal(0.0, 0.007, (n, 8)) * np.r_[1, 1, 1, 1, 1, 1, 0, 1]
    wrong = rng.random(n) < 0.005
    K[wrong, 0] += 0.2
    K = np.clip(K, 0.0, 1.0)
    p = prognose(t, K, seed=0)
    assert set(p.predictions) == set(INDICATOR_COMPONENT)       # every indicator of k
    friction = p.predictions["friction"]
    assert set(friction.excluded) >= set(np.flatnonzero(wrong[:-2]))
    assert indicator_state(friction, t[-1])[0] == "predicted"
    assert 85_000 < friction.lo < friction.median < friction.hi < 160_000   # 0.5 at 400,000 h


def test_the_parsers_names_and_defaults_are_the_modules():
    """The command line's parser reads them from the light emaphm.prognosis.choices (no
    NumPy for `emaphm --help`): they are the ones the modules use."""
    from emaphm.prognosis import choices, inspection, simulator, thresholds

    assert choices.DEGRADATION_SCENARIO_NAMES == tuple(simulator.DEGRADATION_SCENARIOS)
    # the indicators come from the modes' registry, read when the parser checks or shows them
    assert tuple(choices.INDICATORS) == thresholds.INDICATORS
    assert "short_a" in choices.INDICATORS and "short_d" not in choices.INDICATORS
    assert str(choices.FAILURE_DEFAULTS).startswith("friction 0.5, backlash 0.5, short_circuit 0.3")
    assert choices.DEFAULT_RISK == inspection.DEFAULT_RISK == 0.01
    d = inspection.INTERVAL_DEFAULTS["h"]
    assert (d.default, d.min, d.max) == tuple(choices.FLIGHT_HOUR_INTERVALS[k] for k in
                                              ("default", "min", "max"))
