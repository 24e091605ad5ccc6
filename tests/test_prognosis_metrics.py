"""Offline prognostic metrics (Saxena et al. 2010) on hand-computed cases, and the
figures that read them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emaphm.prognosis import metrics
from emaphm.prognosis.simulator import degradation_scenario, inspection_times, synthetic_k_history
from emaphm.prognosis.trends import indicator_series, prognose, rul_track

PNG = b"\x89PNG\r\n\x1a\n"
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


def test_plots_write_pngs(prognosis_case, tmp_path):
    from emaphm.prognosis.plots import plot_alpha_lambda, plot_prognosis

    sc, t, K = prognosis_case
    prog = prognose(t, K, seed=0, actuator="EMA-P")
    fig = plot_prognosis(prog, eol_true={sc.indicator: sc.eol}, path=tmp_path / "p.png")
    assert (tmp_path / "p.png").read_bytes()[:8] == PNG
    assert fig.axes[0].get_title().startswith("short_a")       # nearest threshold first
    y = indicator_series(K)[sc.indicator]
    tr = rul_track(t, y, sc.threshold, seed=0)
    plot_alpha_lambda([tr, tr], sc.eol, labels=["a", "b"], path=tmp_path / "al.png")
    assert (tmp_path / "al.png").read_bytes()[:8] == PNG
    with pytest.raises(ValueError, match="no prediction for indicator"):
        plot_prognosis(prognose(t, K, seed=0, indicators=("friction",)), indicators=("backlash",))
