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
    res = solve(p, CallableSolver(random_search), None, seed=2)
    assert res.algorithm == "random_search" and res.reason == "returned"
    assert res.nfev == p.evaluated == 20 * 50 + 1 and res.fun < 0.05
    again = solve(Box(sphere), CallableSolver(random_search), None, seed=2)
    np.testing.assert_array_equal(res.x, again.x)
    capped = solve(Box(sphere), CallableSolver(random_search), MaxEvaluations(230), seed=2)
    assert capped.reason == "max_evaluations" and capped.nfev == 200   # 4 batches fit, not 5
    with pytest.raises(ValueError, match="fn\\(objective, bounds, rng\\)"):
        CallableSolver(42)


def test_a_solver_written_outside_emaphm_runs_in_the_same_loop():
    """The protocol is all a solver needs: init, step (until state.reason), result."""

    @dataclass(frozen=True)
    class State:
        x: np.ndarray
        f: float
        n: int
        reason: str | None = None

        @property
        def best_f(self):
            return self.f

    class Coordinate:
        name = "coordinate"

        def init(self, problem, termination, seed):
            lo, hi = problem.bounds
            x = (lo + hi) / 2
            return State(x, float(problem.evaluate(x[None])[0]), 1)

        def step(self, problem, state, callback=None):
            X = state.x + np.diag(np.full(state.x.size, 0.25))
            f = problem.evaluate(np.vstack([X, state.x - 0.5 * np.diag(np.full(state.x.size, 0.25))]))
            i = int(np.argmin(f))
            x = np.vstack([X, state.x - 0.125 * np.eye(state.x.size)])[i]
            new = replace(state, n=state.n + f.size)
            if f[i] < state.f:
                new = replace(new, x=x, f=float(f[i]))
            return replace(new, reason="max_evaluations" if new.n >= 50 else None)

        def result(self, state):
            return SolverResult(x=state.x, fun=state.f, nfev=state.n, nit=1,
                                history=np.array([state.f]), reason=state.reason, elapsed_s=0.0,
                                algorithm=self.name, x_raw=state.x, fun_raw=state.f)

    res = solve(Box(sphere, lo=-1.0, hi=3.0), Coordinate(), None, seed=0)
    assert res.reason == "max_evaluations" and res.fun < 1.0 and res.nfev >= 50
