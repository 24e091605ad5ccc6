"""Offline prognostic metrics (Saxena et al. 2010) on hand-computed cases, and the
figures that read them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import assert_png_of, legend_texts, markers

from emaphm.prognosis import metrics
from emaphm.prognosis.simulator import degradation_scenario, inspection_times, synthetic_k_history
from emaphm.prognosis.trends import indicator_series, prognose, rul_track

EOL = 100.0
TIMES = np.array([10.0, 30.0, 50.0, 70.0, 90.0])
TRUE = EOL - TIMES                                      # 90, 70, 50, 30, 10


def test_error_and_relative_accuracy_known_answers():
    pred = np.array([60.0, 75.0, 50.0, 33.0, 5.0])
    np.testing.assert_allclose(metrics.rul_error(TRUE, pred), [30, -5, 0, -3, 5])
    np.testing.assert_allclose(metrics.relative_accuracy(TRUE, pred),
                               [1 - 30 / 90, 1 - 5 / 70, 1.0, 0.9, 0.5])
    assert metrics.cumulative_relative_accuracy(TRUE, pred) == pytest.approx(
        np.mean([1 - 30 / 90, 1 - 5 / 70, 1.0, 0.9, 0.5]))
    assert math.isnan(float(metrics.relative_accuracy(0.0, 3.0)))
    assert metrics.coverage(TRUE, pred - 10, pred + 10) == pytest.approx(0.8)   # first misses


def test_alpha_lambda_points():
    pred = np.array([60.0, 75.0, 50.0, 33.0, 5.0])
    al = metrics.alpha_lambda(TIMES, pred, EOL, alpha=0.2, lambdas=(0.0, 0.5, 0.75, 1.0))
    # t_lambda = 10 + lambda * 90 -> 10, 55, 77.5, 100; last prediction at or before it,
    # counted down to t_lambda
    np.testing.assert_allclose(al.t_lambda, [10, 55, 77.5, 100])
    np.testing.assert_allclose(al.rul_true, [90, 45, 22.5, 0])
    np.testing.assert_allclose(al.rul_pred, [60, 45, 25.5, -5])
    assert al.passed.tolist() == [False, True, True, False]
    assert al.score == 0.5
    assert al.to_dict()["passed"] == [False, True, True, False]


def test_alpha_lambda_distribution_uses_beta():
    rng = np.random.default_rng(0)
    samples = TRUE[:, None] + rng.normal(0.0, 1.0, (5, 2000)) * TRUE[:, None] * 0.15
    al = metrics.alpha_lambda(TIMES, samples, EOL, alpha=0.2, lambdas=(0.5,), beta=0.5)
    # the prediction at t = 50 (mean 50, sd 7.5) counted down to t_lambda = 55: mean 45;
    # bounds 45 +- 0.2 * 45 = +-9 = +-1.2 sd -> mass P(|z| < 1.2) = 0.770
    assert al.mass[0] == pytest.approx(0.770, abs=0.03)
    assert al.passed[0]
    strict = metrics.alpha_lambda(TIMES, samples, EOL, alpha=0.2, lambdas=(0.5,), beta=0.9)
    assert not strict.passed[0]
    inf = np.full((5, 100), np.inf)
    assert metrics.alpha_lambda(TIMES, inf, EOL, lambdas=(0.5,)).mass[0] == 0.0


def test_prognostic_horizon():
    pred = TRUE + np.array([50.0, 15.0, 8.0, -5.0, 2.0])  # within +-10 from the third on
    assert metrics.prognostic_horizon(TIMES, pred, EOL, alpha=0.1) == pytest.approx(50.0)
    assert metrics.prognostic_horizon(TIMES, TRUE, EOL, alpha=0.1) == pytest.approx(90.0)
    assert math.isnan(metrics.prognostic_horizon(TIMES, TRUE + 20, EOL, alpha=0.1))
    # a late excursion resets it
    pred2 = TRUE + np.array([0.0, 0.0, 0.0, 0.0, 30.0])
    assert math.isnan(metrics.prognostic_horizon(TIMES, pred2, EOL, alpha=0.1))


@pytest.mark.parametrize("call, match", [
    (lambda: metrics.alpha_lambda(TIMES[::-1], TRUE, EOL), "strictly increasing"),
    (lambda: metrics.alpha_lambda(TIMES, TRUE[:3], EOL), "predictions must be"),
    (lambda: metrics.alpha_lambda(TIMES, TRUE, EOL, alpha=1.5), "alpha must be in"),
    (lambda: metrics.alpha_lambda(TIMES, TRUE, 5.0), "must come after"),
    (lambda: metrics.alpha_lambda(TIMES, TRUE, EOL, lambdas=(2.0,)), "lambdas must be in"),
    (lambda: metrics.prognostic_horizon(TIMES, TRUE, EOL, beta=0.0), "beta"),
    (lambda: metrics.alpha_mass([], 0, 1), "no RUL samples"),
])
def test_metric_misuse(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ----------------------------------------------------------------------------- figures
@pytest.fixture(scope="module")
def prognosis_case():
    sc = degradation_scenario("short-circuit-growth")
    t = inspection_times(sc.eol, 9)
    K = synthetic_k_history(sc, t, seed=3)
    return sc, t, K


def test_the_rul_figure_shows_trend_threshold_interval_and_the_true_end_of_life(prognosis_case,
                                                                            tmp_path):
    from emaphm.prognosis.plots import plot_prognosis

    sc, t, K = prognosis_case
    prog = prognose(t, K, seed=0, actuator="EMA-P")
    fig = plot_prognosis(prog, eol_true={sc.indicator: sc.eol}, path=tmp_path / "p.png")
    assert_png_of(tmp_path / "p.png", fig)
    ax = fig.axes[0]
    p = prog.predictions[sc.indicator]
    assert ax.get_title().startswith(f"{sc.indicator}: RUL median")   # nearest threshold first
    assert ax.get_title().endswith("flight hours")
    y = indicator_series(K)[sc.indicator]
    (points,) = markers(ax, "o")                            # the identified indicator
    np.testing.assert_array_equal(points.get_xdata(), t)
    np.testing.assert_array_equal(points.get_ydata(), y)
    (median,) = markers(ax, "D")                            # the median RUL, on the threshold
    assert median.get_xdata()[0] == pytest.approx(p.t_now + p.median)
    assert median.get_ydata()[0] == pytest.approx(sc.threshold)
    horizontal = [ln for ln in ax.lines if np.ptp(ln.get_ydata()) == 0 and len(ln.get_ydata()) == 2]
    assert any(ln.get_ydata()[0] == pytest.approx(sc.threshold) for ln in horizontal)
    vertical = [ln for ln in ax.lines if np.ptp(ln.get_xdata()) == 0 and len(ln.get_xdata()) == 2]
    assert sorted(ln.get_xdata()[0] for ln in vertical) == pytest.approx([t[-1], sc.eol])
    # everything drawn is inside the axes: the points, the threshold, the true end of life
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    assert x0 <= t[0] and x1 >= max(sc.eol, p.t_now + p.hi)
    assert y0 <= y.min() and y1 >= max(y.max(), sc.threshold)
    assert fig.axes[-1].get_xlabel() == "time [flight hours]"
    assert ax.get_ylabel() == f"{sc.indicator} [-]"
    assert legend_texts(ax) == ["trend, 90 % cone", f"trend ({p.model})", "identified",
                                "failure threshold", "RUL 90% interval", "median",
                                "true end of life"]
    with pytest.raises(ValueError, match="no prediction for indicator"):
        plot_prognosis(prognose(t, K, seed=0, indicators=("friction",)), indicators=("backlash",))


def _track(median, lo, hi, eol=1000.0):
    t = np.linspace(0.3, 0.9, len(median)) * eol
    return rul_track.__globals__["RULTrack"](
        indicator="friction", threshold=0.5, level=0.9, times=t, n_used=np.arange(len(t)) + 3,
        median=np.asarray(median, float), lo=np.asarray(lo, float), hi=np.asarray(hi, float),
        samples=np.zeros((len(t), 2)))


def test_the_alpha_lambda_figure_draws_every_prediction(prognosis_case, tmp_path):
    from emaphm.prognosis.plots import plot_alpha_lambda

    sc, t, K = prognosis_case
    y = indicator_series(K)[sc.indicator]
    tr = rul_track(t, y, sc.threshold, seed=0)
    fig = plot_alpha_lambda([tr, tr], sc.eol, labels=["a", "b"], path=tmp_path / "al.png")
    assert_png_of(tmp_path / "al.png", fig)
    ax = fig.axes[0]
    assert ax.get_xlabel() == f"share of life t / EoL [-]; EoL = {sc.eol:g} flight hours"
    assert ax.get_ylabel() == "RUL / EoL [-]"
    # the predictions are in the legend, and the mid-life line says what it is
    legend = legend_texts(ax)
    assert legend[:3] == ["true RUL", "alpha = 0.2 cone: true RUL +-20%", "mid-life (t = EoL / 2)"]
    assert legend[-2:] == ["a", "b"]
    (mid,) = [ln for ln in ax.lines if ln.get_label().startswith("mid-life")]
    assert list(mid.get_xdata()) == [0.5, 0.5]
    # every prediction time is inside the axes; every median inside, or counted as off it
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    assert x0 <= (tr.times / sc.eol).min() and x1 >= (tr.times / sc.eol).max()
    med = tr.median / sc.eol
    off = ~(np.isfinite(med) & (med <= y1))
    assert y0 <= np.nanmin(med[np.isfinite(med)])
    assert off.any()              # this early exponential track: the first medians are far off
    (note,) = ax.texts
    assert note.get_text().startswith(f"above the axis, drawn at its edge: {2 * off.sum()} medians")
    assert legend[3] == "off the axis (above 2.5)"


def test_the_alpha_lambda_figure_counts_what_it_clips():
    from emaphm.prognosis.plots import ALPHA_LAMBDA_Y_MAX, plot_alpha_lambda

    rt = np.array([0.7, 0.6, 0.5, 0.4, 0.3, 0.1]) * 1000.0   # true RUL at 0.3, 0.42... of life
    med = rt * 1.1
    med[0], med[1] = 3000.0, np.inf                          # off the axis; threshold not reached
    hi = rt * 1.3
    hi[0], hi[2] = np.inf, 2600.0                            # no upper bound; above the axis
    tr = _track(med, rt * 0.8, hi)
    fig = plot_alpha_lambda([tr], 1000.0)
    ax = fig.axes[0]
    assert ax.get_ylim() == (0.0, ALPHA_LAMBDA_Y_MAX)        # the data reach past the cap
    (note,) = ax.texts
    assert note.get_text() == ("above the axis, drawn at its edge: 2 medians (1 threshold not "
                               "reached), 2 upper bounds (1 unbounded)")
    # one up-triangle at the top edge per clipped prediction: 2 medians, 1 upper bound
    (edge,) = [ln for ln in markers(ax, "^") if len(ln.get_xdata())]
    np.testing.assert_allclose(edge.get_xdata(), tr.times[[0, 1, 2]] / 1000.0 - 0.001)
    assert np.all(np.asarray(edge.get_ydata()) > 0.98 * ALPHA_LAMBDA_Y_MAX)
    assert legend_texts(ax) == ["true RUL", "alpha = 0.2 cone: true RUL +-20%",
                                "mid-life (t = EoL / 2)", f"off the axis (above {ALPHA_LAMBDA_Y_MAX:.2g})",
                                "predicted RUL: median, 90% interval"]
    # the medians that fit are drawn where they are
    (drawn,) = [c for c in ax.containers]
    np.testing.assert_allclose(drawn.lines[0].get_ydata(), med[2:] / 1000.0)
    # without anything to clip, the axis stops above the data and nothing is said
    rt = np.array([0.5, 0.3]) * 1000.0
    fig = plot_alpha_lambda([_track(rt * 1.5, rt, rt * 1.7)], 1000.0)
    ax = fig.axes[0]
    assert ax.get_ylim() == (0.0, 1.3)                       # the default top, above 0.85
    assert len(ax.texts) == 0 and not markers(ax, "^")
