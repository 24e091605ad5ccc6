"""The one solver protocol (:mod:`emaphm.optim.solvers`): every solver is stepped by
``solve(problem, solver, termination, seed=...)`` and stopped by the same terminations.

Known answers on standard test functions, determinism, the budget and callback
contracts, and a solver written outside emaphm running in the same loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from emaphm.optim import DE, PSO, AnyOf, MaxEvaluations, MaxIterations, StallTolerance, WallClock
from emaphm.optim.base import remaining
from emaphm.optim.lsq import MultistartLeastSquares
from emaphm.optim.problems import rosenbrock, sphere
from emaphm.optim.solvers import CallableSolver, Metaheuristic, SolverResult, restart_seeds, solve


@dataclass
class Box:
    """A test problem: a batch function over a box, with a residual form where it has one
    (Rosenbrock: r = [10 (x1 - x0^2), 1 - x0])."""

    fn: object
    lo: float = -2.0
    hi: float = 2.0
    n: int = 2
    fitness_floor: float = 0.0
    evaluated: int = 0

    @property
    def bounds(self):
        return (np.full(self.n, self.lo), np.full(self.n, self.hi))

    def evaluate(self, X):
        self.evaluated += len(X)
        return self.fn(X)

    def residuals(self, X):
        X = np.atleast_2d(X)
        self.evaluated += len(X)
        return np.stack([10.0 * (X[:, 1] - X[:, 0] ** 2), 1.0 - X[:, 0]], axis=1)

    def starts(self):
        return [np.array([-1.2, 1.0])]


def test_termination_says_what_it_leaves():
    assert remaining(None, 10, 1.0) == (math.inf, math.inf)
    assert remaining(MaxEvaluations(100), 30, 1.0) == (70, math.inf)
    assert remaining(WallClock(5.0), 30, 1.5) == (math.inf, 3.5)
    assert remaining(MaxEvaluations(100) | WallClock(5.0), 30, 1.5) == (70, 3.5)
    assert remaining(MaxIterations(3) | StallTolerance(), 30, 1.5) == (math.inf, math.inf)
    assert remaining(AnyOf(MaxEvaluations(10), MaxEvaluations(40)), 5, 0.0) == (5, math.inf)


def test_metaheuristic_solves_the_sphere_and_is_deterministic():
    p = Box(sphere, n=4)
    solver = Metaheuristic(PSO(), polish=False)
    a = solve(p, solver, MaxIterations(60), seed=3)
    b = solve(Box(sphere, n=4), solver, MaxIterations(60), seed=3)
    assert isinstance(a, SolverResult) and a.algorithm == "pso"
    assert a.fun < 1e-3 and a.nit == 60 and a.reason == "max_iterations"
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history, b.history)
    assert a.nfev == p.evaluated == 60 * PSO().pop_size
    assert a.fun == a.fun_raw and a.polish_evaluations == 0


def test_the_polish_refines_and_is_charged_to_the_budget():
    bare = solve(Box(sphere, n=3), Metaheuristic(DE(), polish=False), MaxIterations(20), seed=1)
    p = Box(sphere, n=3)
    polished = solve(p, Metaheuristic(DE()), MaxIterations(20), seed=1)
    assert polished.fun < bare.fun and polished.fun_raw == bare.fun
    assert polished.polish_evaluations > 0 and polished.nfev == p.evaluated
    capped = solve(Box(sphere, n=3), Metaheuristic(DE()), MaxEvaluations(DE().pop_size * 20 + 10),
                   seed=1)
    assert capped.nfev <= DE().pop_size * 20 + 10 + DE().pop_size


def test_restarts_run_while_the_fit_stays_above_the_floor():
    # a floor no fit reaches: every restart runs, with spawned seeds, the best kept
    p = Box(sphere, n=3, fitness_floor=1e-30)
    res = solve(p, Metaheuristic(PSO(pop_size=10), polish=False, restarts=2, restart_ratio=2.0),
                MaxIterations(5), seed=7)
    assert res.starts == 3 and res.nfev == p.evaluated == 3 * 5 * 10
    alone = [solve(Box(sphere, n=3), Metaheuristic(PSO(pop_size=10), polish=False),
                   MaxIterations(5), seed=s).fun for s in (7, *restart_seeds(7, 2))]
    assert res.fun == min(alone)
    # a floor the first run reaches: no restart
    easy = solve(Box(sphere, n=3, fitness_floor=1.0), Metaheuristic(PSO(pop_size=10), polish=False,
                 restarts=2, restart_ratio=2.0), MaxIterations(5), seed=7)
    assert easy.starts == 1


def test_a_callback_stops_any_solver():
    seen = []

    def stop(state):
        seen.append(state.nfev)
        return len(seen) >= 3

    res = solve(Box(sphere), Metaheuristic(PSO(pop_size=10)), None, seed=0, callback=stop)
    assert res.reason == "callback" and res.nit == 3 and res.polish_evaluations == 0
    res = solve(Box(rosenbrock), MultistartLeastSquares(), None, seed=0,
                callback=lambda state: state.nit >= 2)
    assert res.reason == "callback"


def test_least_squares_solver_reaches_rosenbrock_and_screens_a_sample_only_when_needed():
    p = Box(rosenbrock)
    res = solve(p, MultistartLeastSquares(accept_ratio=1.0), None, seed=0)
    assert res.fun < 1e-12 and np.allclose(res.x, 1.0, atol=1e-5)
    assert res.starts == 1 and res.nfev == p.evaluated

    @dataclass
    class WithSample(Box):
        drawn: int = 0
        sample_size: int = 5

        def starts(self):
            return [np.array([-1.9, 1.9])]

        def residuals(self, X):          # a minimum of 0.01 that no start calls good enough
            R = super().residuals(X)
            return np.hstack([R, np.full((R.shape[0], 1), 0.1)])

        def evaluate(self, X):
            R = self.residuals(X)
            return np.sum(R * R, axis=1)

        def sample(self, seed):
            self.drawn += 1
            X = np.random.default_rng(seed).uniform(-2, 2, (self.sample_size, 2))
            return X, self.evaluate(X)

    # far above the floor, every start is tried: the given one, then the sample's best two
    q = WithSample(rosenbrock, fitness_floor=1e-30)
    res = solve(q, MultistartLeastSquares(restarts=2, accept_ratio=1.0, settle_ratio=2.0), None,
                seed=4)
    assert q.drawn == 1 and res.starts == 3 and res.nfev == q.evaluated
    assert res.fun == pytest.approx(0.01) and np.allclose(res.x, 1.0, atol=1e-4)
    # below the settle level, a further start that gains less than 1 % ends the starts
    settled = solve(WithSample(rosenbrock, fitness_floor=1.0),
                    MultistartLeastSquares(restarts=2, settle_ratio=2.0), None, seed=4)
    assert settled.starts == 2
    tight = WithSample(rosenbrock, fitness_floor=1e-30)
    capped = solve(tight, MultistartLeastSquares(restarts=2), MaxEvaluations(8), seed=4)
    assert tight.drawn == 0 and capped.nfev <= 8      # no room for the sample and a start


def random_search(objective, bounds, rng):
    """A plain function as a solver: 20 batches of 50 uniform points, keep the best."""
    lo, hi = bounds
    best, f_best = None, math.inf
    for _ in range(20):
        X = rng.uniform(lo, hi, (50, lo.size))
        f = objective(X)
        i = int(np.argmin(f))
        if f[i] < f_best:
            best, f_best = X[i], f[i]
    return best


def test_a_plain_function_is_a_solver_and_its_budget_is_enforced():
    p = Box(sphere)
    bare = CallableSolver(random_search, polish=False)
    res = solve(p, bare, None, seed=2)
    assert res.algorithm == "random_search" and res.reason == "returned"
    assert res.nfev == p.evaluated == 20 * 50 + 1 and res.fun < 0.05
    again = solve(Box(sphere), bare, None, seed=2)
    np.testing.assert_array_equal(res.x, again.x)
    capped = solve(Box(sphere), bare, MaxEvaluations(230), seed=2)
    assert capped.reason == "max_evaluations" and capped.nfev == 200   # 4 batches fit, not 5
    with pytest.raises(ValueError, match="fn\\(objective, bounds, rng\\)"):
        CallableSolver(42)


def test_a_plain_function_is_polished_and_its_budget_holds_the_polish_back():
    """Issue 34: a function gets the polish a metaheuristic gets, under a budget too."""
    free = solve(Box(sphere), CallableSolver(random_search), None, seed=2)
    assert free.polish_evaluations > 0 and free.fun < free.fun_raw and free.skipped == {}
    p = Box(sphere)
    capped = solve(p, CallableSolver(random_search), MaxEvaluations(230), seed=2)
    # the function gets 230 less 23 (POLISH_SHARE): four batches fit; the polish the rest
    assert capped.fun_raw == solve(Box(sphere), CallableSolver(random_search, polish=False),
                                   MaxEvaluations(207), seed=2).fun
    assert capped.polish_evaluations > 0 and capped.nfev == p.evaluated <= 230
    assert capped.fun < capped.fun_raw


def one_at_a_time(objective, bounds, rng):
    """A plain function that evaluates uniform points one by one until stopped."""
    lo, hi = bounds
    while True:
        objective(rng.uniform(lo, hi, (1, lo.size)))


def test_a_budget_too_small_for_the_polish_says_so():
    res = solve(Box(sphere, n=3), CallableSolver(one_at_a_time), MaxEvaluations(20), seed=2)
    assert res.polish_evaluations == 0 and "fewer than one poll" in res.skipped["polish"]
    res = solve(Box(sphere, n=3), Metaheuristic(PSO(pop_size=10)), MaxEvaluations(12), seed=2)
    assert res.polish_evaluations == 0 and "fewer than one poll" in res.skipped["polish"]


def test_a_plain_function_is_restarted_each_run_with_the_budget():
    p = Box(sphere, n=3, fitness_floor=1e-30)          # a floor no fit reaches
    solver = CallableSolver(random_search, restarts=2, restart_ratio=2.0, polish=False)
    res = solve(p, solver, MaxEvaluations(800), seed=7)
    assert res.starts == 3 and res.nfev == p.evaluated == 3 * 800    # 16 batches a run
    alone = [solve(Box(sphere, n=3), CallableSolver(random_search, polish=False),
                   MaxEvaluations(800), seed=s).fun for s in (7, *restart_seeds(7, 2))]
    assert res.fun == min(alone)
    assert "after the 2 restart(s) allowed" in res.skipped["restarts"]
    once = solve(Box(sphere, n=3, fitness_floor=1e-30),
                 CallableSolver(random_search, restart_ratio=2.0), MaxEvaluations(800), seed=7)
    assert once.starts == 1 and "no restart was allowed" in once.skipped["restarts"]
    assert "give restarts=N" in once.skipped["restarts"]


def test_a_budget_holds_back_the_polish_of_each_run():
    """Issue 34: PSO under a budget is polished (it used to spend the budget and skip it);
    each restart gets the budget again, less its polish's share."""
    pso = PSO(pop_size=10)
    p = Box(sphere, n=3)
    one = solve(p, Metaheuristic(pso), MaxEvaluations(500), seed=1)
    assert one.polish_evaluations > 0 and one.nfev == p.evaluated <= 500 + 10
    assert one.run_evaluations - one.polish_evaluations <= 450 + 10 and one.skipped == {}
    p = Box(sphere, n=3, fitness_floor=1e-30)
    three = solve(p, Metaheuristic(pso, restarts=2, restart_ratio=2.0), MaxEvaluations(500),
                  seed=1)
    assert three.starts == 3 and three.nfev == p.evaluated <= 3 * (500 + 10)
    assert three.polish_evaluations > 0
    w = solve(Box(sphere, n=3), Metaheuristic(pso), WallClock(0.5), seed=1)
    assert w.polish_evaluations > 0 and w.elapsed_s < 1.0
