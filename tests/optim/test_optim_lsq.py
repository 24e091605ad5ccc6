"""Batched least squares (emaphm.optim.lsq): known answers, bounds, budgets, determinism."""

import numpy as np
import pytest

from emaphm.optim.lsq import LSQState, least_squares_batched, multistart_least_squares


def rosenbrock(X):
    """Residuals of Rosenbrock's function, batched: minimum 0 at (1, 1)."""
    X = np.atleast_2d(X)
    return np.stack([10.0 * (X[:, 1] - X[:, 0] ** 2), 1.0 - X[:, 0]], axis=1)


class Spy:
    """A residual function that records the batch sizes it was called with."""

    def __init__(self, f):
        self.f, self.sizes = f, []

    def __call__(self, X):
        self.sizes.append(X.shape[0])
        return self.f(X)


BOX = ([-2.0, -2.0], [2.0, 2.0])


def test_rosenbrock_is_solved_in_few_batched_evaluations():
    spy = Spy(rosenbrock)
    res = least_squares_batched(spy, [-1.2, 1.0], BOX, diff_step=1e-6)
    assert res.x == pytest.approx([1.0, 1.0], abs=1e-6)
    assert res.fun < 1e-12 and res.reason == "converged"
    # each Jacobian is ONE call of n = 2 points; the rest are single points
    assert set(spy.sizes) == {1, 2} and spy.sizes.count(2) == res.nit
    assert res.nfev == sum(spy.sizes) < 100          # measured 45
    assert np.all(np.diff(res.history) <= 0.0)


def test_bounds_are_respected_and_the_bounded_minimum_found():
    """Box x0 <= 0.5: the constrained minimum of Rosenbrock is at (0.5, 0.25)."""
    seen = []

    def f(X):
        seen.append(X.copy())
        return rosenbrock(X)

    res = least_squares_batched(f, [0.0, 0.0], ([-2.0, -2.0], [0.5, 2.0]), diff_step=1e-6)
    assert res.x == pytest.approx([0.5, 0.25], abs=1e-5)
    X = np.vstack(seen)
    assert X[:, 0].max() <= 0.5 and X[:, 0].min() >= -2.0   # differences taken inward


def test_a_start_that_diverges_is_a_value_not_an_error():
    def f(X):
        R = rosenbrock(X)
        R[X[:, 0] < -1.0] = np.inf
        return R

    res = least_squares_batched(f, [-1.5, 0.0], BOX)
    assert res.fun == np.inf and res.reason == "not_finite" and res.nfev == 1


def test_a_diverged_neighbour_does_not_stop_the_search():
    """Points beyond x0 > 1.5 diverge; the search from inside still converges."""
    def f(X):
        R = rosenbrock(X)
        R[X[:, 0] > 1.5] = np.nan
        return R

    res = least_squares_batched(f, [0.0, 0.0], BOX, diff_step=1e-6)
    assert res.x == pytest.approx([1.0, 1.0], abs=1e-5)


def test_the_evaluation_budget_is_a_hard_cap():
    spy = Spy(rosenbrock)
    res = least_squares_batched(spy, [-1.2, 1.0], BOX, max_evals=10)
    assert res.reason == "max_evaluations" and res.nfev <= 10 and sum(spy.sizes) <= 10
    assert np.isfinite(res.fun)                          # the best point seen is kept


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="diff_step must be > 0"):
        least_squares_batched(rosenbrock, [0, 0], BOX, diff_step=0.0)
    with pytest.raises(ValueError, match="shape"):
        least_squares_batched(lambda X: np.zeros(3), [0, 0], BOX)
    with pytest.raises(ValueError, match="at least one start"):
        multistart_least_squares(rosenbrock, [], BOX)


def two_basins(X):
    """``(x^2 - 1)^2 + 0.09 (x - 1)^2 + y^2``: the global minimum 0 at (1, 0) and a local
    one near x = -0.955 (sum of squares 0.35) behind a ridge at x = 0."""
    X = np.atleast_2d(X)
    x, y = X[:, 0], X[:, 1]
    return np.stack([x * x - 1.0, 0.3 * (x - 1.0), y], axis=1)


def test_multistart_stops_at_the_first_start_good_enough():
    starts = [np.array([1.2, 0.5]), np.array([-1.2, 0.5])]
    res, info = multistart_least_squares(two_basins, starts, BOX, accept=1e-8, polish_evals=0)
    assert info["starts"] == 1 and res.x[0] == pytest.approx(1.0, abs=1e-4)


def test_multistart_goes_on_from_the_next_start_after_a_local_minimum():
    starts = [np.array([-1.2, 0.5]), np.array([1.2, 0.5])]
    res, info = multistart_least_squares(two_basins, starts, BOX, accept=1e-8, polish_evals=0)
    assert info["starts"] == 2 and res.x[0] == pytest.approx(1.0, abs=1e-4) and res.fun < 1e-8
    # starts are taken lazily: a generator is consumed only as far as needed
    consumed = []

    def gen():
        for s in ([1.2, 0.5], [-1.2, 0.5], [0.3, 0.3]):
            consumed.append(s)
            yield np.array(s)

    multistart_least_squares(two_basins, gen(), BOX, accept=1e-8, polish_evals=0)
    assert consumed == [[1.2, 0.5]]


def test_multistart_polish_and_callback():
    calls = []

    def cb(state):
        assert isinstance(state, LSQState) and state.nfev > 0
        calls.append(state.best_f)
        return len(calls) >= 3                           # stop at the third iteration

    starts = [np.array([-1.2, 0.5]), np.array([1.2, 0.5])]
    res, info = multistart_least_squares(two_basins, starts, BOX, accept=1e-8, callback=cb)
    assert res.reason == "callback" and info["starts"] == 1 and len(calls) == 3
    assert calls == sorted(calls, reverse=True)         # best so far never worsens
    assert info["polish_evaluations"] == 0               # no polish after a stop
    res2, info2 = multistart_least_squares(rosenbrock, [np.array([-1.2, 1.0])], BOX, polish_evals=50)
    assert 0 < info2["polish_evaluations"] <= 50 and res2.fun <= info2["f_raw"]


def test_deterministic():
    starts = [np.array([-1.2, 0.5]), np.array([1.2, 0.5])]
    a, _ = multistart_least_squares(two_basins, starts, BOX, accept=1e-8)
    b, _ = multistart_least_squares(two_basins, starts, BOX, accept=1e-8)
    np.testing.assert_array_equal(a.x, b.x)
    assert a.fun == b.fun and a.nfev == b.nfev


def test_the_history_shows_the_descent_of_each_pass():
    """The best fitness after each Jacobian, from the start's down to the final one (not
    the final value throughout)."""
    res, info = multistart_least_squares(rosenbrock, [np.array([-1.2, 1.0])], BOX, polish_evals=0)
    h = res.history
    assert h[0] == pytest.approx(24.2, rel=1e-9)              # ||r(-1.2, 1)||^2 = 19.36 + 4.84
    assert h[-1] == pytest.approx(res.fun) and h[-1] < 1e-10
    assert np.all(np.diff(h) <= 0.0) and len(set(h.tolist())) > 5
