"""The trend shapes (:mod:`emaphm.prognosis.shapes`): each one consistent with itself.

Properties every registered shape must have: the Jacobian is the derivative of the value,
the growth is the value's slope at the last inspection (and its gradient the growth's
derivative), a crossing time puts the trend on the threshold, a fit of a noise-free trend
of the shape gives its parameters back. A shape that leaves a method out fails loudly.
"""

from __future__ import annotations

import numpy as np
import pytest

from emaphm.prognosis.shapes import SHAPES, TrendShape, crossing_tau
from emaphm.prognosis.trends import TREND_MODELS, fit_trend

TAU = np.linspace(-900.0, 0.0, 19)
#: a rising trend of each shape: (theta, a threshold it crosses after t_ref)
RISING = {"linear": ([0.1, 2e-4], 0.3), "exponential": ([np.log(0.1), 1e-3], 0.3),
          "quadratic": ([0.1, 2e-4, 1e-7], 0.3), "onset": ([0.1, 2e-4, -420.0], 0.3)}


def test_the_registry_is_what_the_trends_fit():
    assert TREND_MODELS == tuple(SHAPES) and set(RISING) == set(SHAPES)
    for name, shape in SHAPES.items():
        assert shape.name == name and len(RISING[name][0]) == shape.n_params


@pytest.mark.parametrize("name", list(SHAPES))
def test_jacobian_growth_and_crossing_agree_with_the_value(name):
    shape = SHAPES[name]
    theta, threshold = (np.array(RISING[name][0], dtype=float), RISING[name][1])
    J = shape.jacobian(theta, TAU)
    for i in range(shape.n_params):
        h = 1e-6 * max(abs(theta[i]), 1e-3)
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        fd = (shape.value(up, TAU) - shape.value(down, TAU)) / (2 * h)
        np.testing.assert_allclose(J[:, i], fd, rtol=1e-5, atol=1e-9)
    rate, grad = shape.growth(theta)
    eps = 1e-3
    slope = (shape.value(theta, np.array([eps])) - shape.value(theta, np.array([-eps]))) / (2 * eps)
    assert rate == pytest.approx(float(slope[0]), rel=1e-5)
    for i in range(shape.n_params):
        h = 1e-6 * max(abs(theta[i]), 1e-3)
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        assert grad[i] == pytest.approx((shape.growth(up)[0] - shape.growth(down)[0]) / (2 * h),
                                        rel=1e-4, abs=1e-12)
    tau = crossing_tau(shape, theta[None, :], threshold)[0]
    assert 0.0 < tau < np.inf
    assert float(shape.value(theta, np.array([tau]))[0]) == pytest.approx(threshold, rel=1e-9)
    # at or past the threshold already: failed at t_ref; falling: never
    assert crossing_tau(shape, theta[None, :], 0.01)[0] == 0.0
    falling = theta.copy()
    falling[1] = -falling[1]
    if name == "quadratic":
        falling[2] = -falling[2]
    assert crossing_tau(shape, falling[None, :], threshold)[0] == np.inf


@pytest.mark.parametrize("name", list(SHAPES))
def test_a_noise_free_trend_is_fitted_back(name):
    shape = SHAPES[name]
    theta = np.array(RISING[name][0], dtype=float)
    y = shape.value(theta, TAU)
    f = fit_trend(TAU + 1000.0, y, name)
    np.testing.assert_allclose(f.theta, theta, rtol=1e-5, atol=1e-9)
    assert f.rss < 1e-16 * float(y @ y)


def test_a_shape_that_leaves_a_method_out_fails_loudly():
    class Half(TrendShape):
        name, n_params = "half", 2

        def value(self, theta, tau):
            return theta[..., 0:1] + 0.0 * tau

    with pytest.raises(NotImplementedError, match="Half.level_and_time"):
        crossing_tau(Half(), np.zeros((1, 2)), 1.0)
    with pytest.raises(NotImplementedError, match="Half.growth"):
        Half().growth(np.zeros(2))
