"""Bounded nonlinear least squares with batched finite differences, from several starts.

The metaheuristics minimise a scalar; many objectives are sums of squares,
``f(x) = ||r(x)||^2``, and then a Gauss-Newton / trust-region method reaches the
minimum of a basin in tens of evaluations where a population needs thousands.
:func:`least_squares_batched` wraps :func:`scipy.optimize.least_squares`
(``method="trf"``, bounds) and computes its Jacobian by forward differences in ONE
call of a batch residual function ``R(X) -> (m, n_res)`` over the ``n`` perturbed
points, the way the batch kernels are cheapest; :func:`multistart_least_squares`
runs it from a list of starts until one is good enough, refines the best with a
coarse and then a fine difference step (a coarse step sees through the small-scale
roughness that dry friction and backlash put on a sampled residual, a fine one
converges), and polishes it with :func:`emaphm.optim.local.compass_search`.

Like the rest of :mod:`emaphm.optim` this knows nothing about actuators: points are
in the box, residual rows that are not finite (a diverged simulation) count as an
infinite fitness, never as an error. Deterministic: no random numbers.
"""

from __future__ import annotations

import itertools
import math
import sys
import time
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from .base import OptimizeResult, as_bounds, remaining
from .local import compass_search
from .solvers import SolverResult, _skipped_polish

__all__ = ["least_squares_batched", "multistart_least_squares", "MultistartLeastSquares",
           "LeastSquaresState", "LSQState", "DIFF_STEPS"]

#: Forward-difference steps, as fractions of each bound's width, of the three passes of
#: :func:`multistart_least_squares`: from every start, then coarse and fine refinement of
#: the best (``benchmarks/bench_identification.py`` measured 1e-3 alone to stop in the
#: roughness of a backlash valley, and 3e-2 alone to settle beside a short circuit).
DIFF_STEPS = (1e-3, 3e-2, 1e-3)


@dataclass(frozen=True)
class LSQState:
    """Progress of :func:`multistart_least_squares`, passed to its callback (the
    fields of :class:`emaphm.optim.base.State` a callback reads)."""

    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray
    start: int


class _Budget(Exception):
    """Raised inside the residual function when the evaluation or time budget is spent."""


class _Stop(Exception):
    """Raised inside the Jacobian when the callback asks to stop."""


class _Counted:
    """The residual function with an evaluation count, a budget and a one-point cache
    (SciPy asks for ``r(x)`` and then the Jacobian at the same ``x``)."""

    def __init__(self, residuals: Callable[[np.ndarray], np.ndarray], max_evals: float,
                 deadline: float) -> None:
        self.residuals, self.max_evals, self.deadline = residuals, max_evals, deadline
        self.nfev = 0
        self._key: bytes | None = None
        self._r: np.ndarray | None = None

    def batch(self, X: np.ndarray) -> np.ndarray:
        if self.nfev + X.shape[0] > self.max_evals or time.perf_counter() > self.deadline:
            raise _Budget
        R = np.asarray(self.residuals(X), dtype=float)
        self.nfev += X.shape[0]
        if R.ndim != 2 or R.shape[0] != X.shape[0]:
            raise ValueError(f"residuals must return shape ({X.shape[0]}, n_res), got {R.shape}")
        return R

    def at(self, x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key != self._key:
            self._r = self.batch(x[None, :])[0]
            self._key = key
        return self._r


def _sse(r: np.ndarray) -> float:
    return float(r @ r) if np.all(np.isfinite(r)) else np.inf


def _forward_differences(f: _Counted, x: np.ndarray, r0: np.ndarray, step: np.ndarray) -> np.ndarray:
    """The Jacobian (n_res, n) by forward differences of ``step``, in one batch call."""
    R = f.batch(x[None, :] + np.diag(step))
    J = (R - r0[None, :]) / step[:, None]
    J[~np.isfinite(J)] = 0.0               # a diverged neighbour tells nothing
    return J.T


def least_squares_batched(residuals: Callable[[np.ndarray], np.ndarray], x0: Any, bounds: Any, *,
                          diff_step: float | Sequence[float] = 1e-3, max_evals: float = 2000,
                          max_seconds: float = float("inf"), xtol: float = 1e-4,
                          ftol: float = 1e-6, gtol: float = 1e-12, max_nfev: int = 60,
                          x_scale: Any = None,
                          jac: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                          callback: Callable[[np.ndarray, float, int, int], bool | None] | None = None,
                          full_output: bool = False) -> Any:
    """Minimise ``||r(x)||^2`` inside ``bounds`` from ``x0``.

    ==========  ======  ==========================================================
    argument    unit    meaning
    ==========  ======  ==========================================================
    residuals   --      ``R(X)``: (m, n) points -> (m, n_res) residuals, in one call
    x0          --      start, problem coordinates, inside the box
    diff_step   unit    forward-difference step as a fraction of each bound's width
                        (a scalar or one per variable); taken inward at a bound
    max_evals   --      residual evaluations (points) this call may spend
    max_seconds s       wall-clock budget
    xtol, ftol  --      SciPy's tolerances on the step and on the cost reduction
                        (defaults 1e-4, 1e-6: tighter ones cost a sixth more evaluations
                        for a change far below the model's own error)
    gtol        --      SciPy's tolerance on the gradient
    max_nfev    --      SciPy's limit on its own calls of ``r`` (steps tried)
    x_scale     --      SciPy's variable scales (default: each bound's width)
    jac         --      ``jac(x, r(x)) -> (n_res, n)``: the Jacobian, where the caller
                        knows it better (some columns exactly, or steps of its own);
                        default: forward differences, one batch call
    callback    --      ``callback(best_x, best_f, nfev, nit)`` before each Jacobian;
                        True stops (reason ``"callback"``)
    full_output --      also return SciPy's own result (its ``x``, residual ``fun`` and
                        ``jac`` at the solution, for a covariance), None where SciPy did
                        not finish
    ==========  ======  ==========================================================

    Returns an :class:`~emaphm.optim.base.OptimizeResult` whose ``fun`` is
    ``||r(x)||^2`` (``inf`` where ``r(x0)`` is not finite), ``nfev`` counts points
    (Jacobian batches included), ``nit`` the Jacobians and ``reason`` is
    ``"converged"``, ``"max_iterations"``, ``"max_evaluations"``, ``"wall_clock"``,
    ``"callback"`` or ``"not_finite"``. The BLAS SciPy calls runs on one thread (a thread pool
    spinning beside busy cores made each small SVD up to 60x slower).
    """
    from scipy.optimize import least_squares
    from threadpoolctl import threadpool_limits

    t0 = time.perf_counter()
    b = as_bounds(bounds)
    x0 = np.clip(np.asarray(x0, dtype=float), b.lo, b.hi)
    n = x0.size
    h = np.broadcast_to(np.asarray(diff_step, dtype=float), (n,)) * (b.hi - b.lo)
    if not np.all(h > 0):
        raise ValueError(f"diff_step must be > 0, got {diff_step!r}")
    f = _Counted(residuals, max_evals, t0 + max_seconds)
    best = {"x": x0, "f": np.inf}
    history: list[float] = []

    def fun(x: np.ndarray) -> np.ndarray:
        r = f.at(x)
        s = _sse(r)
        if s < best["f"]:
            best["x"], best["f"] = x.copy(), s
        return r

    def jacobian(x: np.ndarray) -> np.ndarray:
        r0 = f.at(x)
        history.append(best["f"])
        if callback is not None and callback(best["x"], best["f"], f.nfev, len(history)):
            raise _Stop
        if jac is not None:
            return np.asarray(jac(x, r0), dtype=float)
        return _forward_differences(f, x, r0, np.where(x + h <= b.hi, h, -h))

    reason = "converged"
    res = None
    try:
        r0 = f.at(x0)
        if not np.all(np.isfinite(r0)):
            out = OptimizeResult(x=x0, fun=np.inf, nfev=f.nfev, nit=0, history=np.array([np.inf]),
                                 reason="not_finite", elapsed_s=time.perf_counter() - t0,
                                 algorithm="lsq")
            return (out, None) if full_output else out
        best["x"], best["f"] = x0.copy(), _sse(r0)
        with threadpool_limits(limits=1, user_api="blas"):
            res = least_squares(fun, x0, jac=jacobian, bounds=(b.lo, b.hi), method="trf",
                                x_scale=b.hi - b.lo if x_scale is None else x_scale, xtol=xtol,
                                ftol=ftol, gtol=gtol, max_nfev=max_nfev)
        if res.status == 0:
            reason = "max_iterations"
    except _Budget:
        reason = "wall_clock" if time.perf_counter() > f.deadline else "max_evaluations"
    except _Stop:
        reason = "callback"
    history.append(best["f"])
    out = OptimizeResult(x=best["x"], fun=float(best["f"]), nfev=f.nfev, nit=len(history) - 1,
                         history=np.minimum.accumulate(np.asarray(history)), reason=reason,
                         elapsed_s=time.perf_counter() - t0, algorithm="lsq")
    return (out, res) if full_output else out


@dataclass(frozen=True, eq=False)
class LeastSquaresState:
    """Progress of :class:`MultistartLeastSquares` (one pass, or the polish, per step).

    ``pending``: the starts not run yet (an iterator over ``problem.starts()``, then the
    best of the screened sample); ``phase``: ``"starts"``, ``"refine"`` or ``"polish"``;
    ``best``: the best pass so far; ``nfev``: evaluations of the passes and the polish,
    ``charged``: of the screened sample; ``stop``: ``"converged"`` or the reason a budget
    or the callback stopped the passes."""

    termination: Any
    seed: int
    t0: float
    pending: Iterator[np.ndarray]
    phase: str = "starts"
    sampled: bool = False
    n_run: int = 0
    best: OptimizeResult | None = None
    history: tuple = ()
    nfev: int = 0
    charged: int = 0
    nit: int = 0
    refine: int = 1
    stop: str = "converged"
    x_raw: np.ndarray | None = None
    f_raw: float = math.inf
    polish_evaluations: int = 0
    polish_s: float = 0.0
    reason: str | None = None
    skipped: dict | None = None

    @property
    def best_x(self) -> np.ndarray | None:
        return None if self.best is None else self.best.x

    @property
    def best_f(self) -> float:
        return math.inf if self.best is None else self.best.fun


@dataclass(frozen=True)
class MultistartLeastSquares:
    """Least squares from each start in turn until one is good enough; the best refined and
    polished. A solver of :mod:`emaphm.optim.solvers` (``init``/``step``/``result``).

    1. From each of ``problem.starts()`` (in order), then, when those are spent and the
       budget leaves room for it and one more start, from the best finite points of the
       problem's screened ``sample(seed)`` (its ``sample_size`` evaluations charged to the
       budget): :func:`least_squares_batched` with step ``diff_steps[0]``, at most
       ``1 + restarts`` starts in all. Stop as soon as the best ``||r||^2`` is at or below
       ``accept_ratio`` times the problem's ``fitness_floor``, or, once the best is at or
       below ``settle_ratio`` times it, when a further start improved it by less than the
       fraction ``min_gain`` (the fit is then limited by the model, not by the basin the
       first start fell into; above it every start is tried).
    2. From the best point, one pass with each further step of ``diff_steps`` (a pass
       that does not improve is dropped).
    3. :func:`~emaphm.optim.local.compass_search` of the best point (step 0.02 of the
       box down to 1e-3, at most ``polish_evaluations`` points; 0: none): derivative-free,
       so it settles what the differences could not resolve.

    An evaluation or wall-clock termination caps everything (each pass gets what is left;
    the polish follows passes that converged); a polish not made is said, with the reason,
    in the result's ``skipped``.
    The callback is called before each Jacobian with a :class:`LSQState`. Deterministic:
    the only random numbers are the problem's sample, drawn from the seed.
    """

    restarts: int = 3
    accept_ratio: float = 0.0
    settle_ratio: float = math.inf
    diff_steps: tuple[float, ...] = DIFF_STEPS
    polish_evaluations: int = 200
    min_gain: float = 0.01
    name = "lsq"
    kind = "least_squares"

    def __post_init__(self) -> None:
        if isinstance(self.restarts, bool) or not isinstance(self.restarts, (int, np.integer)) \
                or self.restarts < 0:
            raise ValueError(f"restarts must be an integer >= 0, got {self.restarts!r}")
        if len(self.diff_steps) < 1:
            raise ValueError("diff_steps needs at least one step")
        if isinstance(self.polish_evaluations, bool) or self.polish_evaluations < 0:
            raise ValueError(f"polish_evaluations must be an integer >= 0, got "
                             f"{self.polish_evaluations!r}")

    def init(self, problem: Any, termination: Any, seed: int) -> LeastSquaresState:
        return LeastSquaresState(termination, seed, time.perf_counter(),
                                 itertools.islice(iter(problem.starts()), 1 + self.restarts))

    def _limits(self, problem: Any) -> tuple[float, float]:
        floor = float(getattr(problem, "fitness_floor", 0.0) or 0.0)
        return self.accept_ratio * floor, (self.settle_ratio * floor if floor > 0 else math.inf)

    def _left(self, state: LeastSquaresState) -> tuple[float, float]:
        return remaining(state.termination, state.nfev + state.charged,
                         time.perf_counter() - state.t0)

    def _next_start(self, problem: Any, state: LeastSquaresState) -> tuple[Any, LeastSquaresState]:
        """The next start, drawing the screened sample when the given starts are spent."""
        x = next(state.pending, None)
        if x is not None or state.sampled:
            return x, state
        state = replace(state, sampled=True)
        n_sample = int(getattr(problem, "sample_size", 0) or 0)
        room = 1 + self.restarts - state.n_run
        n_var = as_bounds(problem.bounds).n_var
        if n_sample <= 0 or room <= 0 or self._left(state)[0] < n_sample + n_var + 1:
            return None, state
        X, y = problem.sample(state.seed)
        y = np.asarray(y, dtype=float)
        picks = [X[i] for i in np.argsort(y, kind="stable")[:self.restarts] if np.isfinite(y[i])]
        state = replace(state, charged=state.charged + n_sample,
                        pending=itertools.islice(iter(picks), room))
        return next(state.pending, None), state

    def _pass(self, problem: Any, state: LeastSquaresState, x: np.ndarray, step: float,
              callback: Any) -> tuple[bool, LeastSquaresState]:
        """One least-squares pass; False when the search must stop (budget or callback)."""
        b = as_bounds(problem.bounds)
        evals, seconds = self._left(state)
        if evals < b.n_var + 1 or seconds <= 0:
            return False, replace(state, stop="max_evaluations" if evals < b.n_var + 1
                                  else "wall_clock")
        best = state.best

        def each(x_best: np.ndarray, f_best: float, n_ev: int, n_it: int) -> bool:
            if best is not None and best.fun <= f_best:
                x_best, f_best = best.x, best.fun
            hist = np.minimum.accumulate(np.append(np.asarray(state.history, dtype=float), f_best))
            return bool(callback(LSQState(x_best, f_best, state.nfev + n_ev, state.nit + n_it,
                                          hist, state.n_run)))

        r = least_squares_batched(problem.residuals, x, b, diff_step=step, max_evals=evals,
                                  max_seconds=seconds, callback=None if callback is None else each)
        before = np.inf if best is None else best.fun
        state = replace(state, nfev=state.nfev + r.nfev, nit=state.nit + r.nit,
                        best=r if best is None or r.fun < best.fun else best,
                        history=state.history + tuple(np.minimum(r.history, before).tolist()))
        if r.reason in ("max_evaluations", "wall_clock", "callback"):
            return False, replace(state, stop=r.reason)
        return True, state

    def step(self, problem: Any, state: LeastSquaresState, callback: Any = None) -> LeastSquaresState:
        if state.phase == "starts":
            x, state = self._next_start(problem, state)
            if x is None:
                if state.n_run == 0:
                    raise ValueError("multistart least squares needs at least one start")
                return replace(state, phase="refine")
            accept, settle = self._limits(problem)
            state = replace(state, n_run=state.n_run + 1)
            before = state.best_f
            going, state = self._pass(problem, state, np.asarray(x, dtype=float),
                                      self.diff_steps[0], callback)
            if not going:
                return replace(state, phase="polish")
            f = state.best_f
            if f <= accept or (state.n_run > 1 and f <= settle and f > (1 - self.min_gain) * before):
                return replace(state, phase="refine")
            return state
        if state.phase == "refine":
            if state.refine >= len(self.diff_steps) or not np.isfinite(state.best_f):
                return replace(state, phase="polish")
            going, state = self._pass(problem, state, state.best.x, self.diff_steps[state.refine],
                                      callback)
            return replace(state, refine=state.refine + 1, phase="refine" if going else "polish")
        return self._polish(problem, state)

    def _polish(self, problem: Any, state: LeastSquaresState) -> LeastSquaresState:
        b = as_bounds(problem.bounds)
        best = state.best
        state = replace(state, x_raw=best.x, f_raw=best.fun)
        evals, seconds = self._left(state)
        why = "" if self.polish_evaluations == 0 else (
            _skipped_polish(best.fun, state.stop, evals, seconds, b.n_var)
            or ("" if state.stop == "converged" else
                f"the budget stopped the least-squares passes ({state.stop}); its polish is "
                "made only after they converge: give a larger budget"))
        state = replace(state, skipped={"polish": why} if why else {})
        if self.polish_evaluations > 0 and not why:
            pol = compass_search(problem.evaluate, best.x, b, f0=best.fun, step=0.02, tol=1e-3,
                                 max_evals=int(min(self.polish_evaluations, evals)),
                                 max_seconds=seconds)
            state = replace(state, nfev=state.nfev + pol.nfev, polish_evaluations=pol.nfev,
                            polish_s=pol.elapsed_s,
                            history=state.history + tuple(np.asarray(pol.history[1:], dtype=float)))
            if pol.fun < best.fun:
                state = replace(state, best=replace(best, x=pol.x, fun=float(pol.fun)))
        return replace(state, phase="done", reason=state.stop)

    def result(self, state: LeastSquaresState) -> SolverResult:
        best = state.best
        return SolverResult(
            x=best.x, fun=float(best.fun), nfev=state.nfev + state.charged, nit=state.nit,
            history=np.minimum.accumulate(np.asarray(state.history, dtype=float)),
            reason=state.reason, elapsed_s=time.perf_counter() - state.t0, algorithm=self.name,
            x_raw=state.x_raw, fun_raw=float(state.f_raw), starts=state.n_run,
            polish_evaluations=state.polish_evaluations, polish_s=state.polish_s,
            run_evaluations=state.nfev, skipped=dict(state.skipped or {}))


@dataclass(frozen=True)
class _Given:
    """A residual function and its starts as a problem of :class:`MultistartLeastSquares`."""

    residuals: Callable[[np.ndarray], np.ndarray]
    starts_: Iterable[Any]
    bounds: Any
    fitness: Callable[[np.ndarray], np.ndarray] | None

    fitness_floor = 1.0

    def starts(self) -> Iterable[Any]:
        return self.starts_

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        if self.fitness is not None:
            return self.fitness(X)
        R = np.asarray(self.residuals(X), dtype=float)
        out = np.einsum("ij,ij->i", R, R)
        out[~np.isfinite(out)] = np.inf
        return out


def multistart_least_squares(residuals: Callable[[np.ndarray], np.ndarray],
                             starts: Iterable[Any], bounds: Any, *, accept: float = 0.0,
                             diff_steps: Sequence[float] = DIFF_STEPS, polish_evals: int = 200,
                             max_evals: float = float("inf"), max_seconds: float = float("inf"),
                             callback: Callable[[LSQState], bool | None] | None = None,
                             fitness: Callable[[np.ndarray], np.ndarray] | None = None,
                             min_gain: float = 0.01, settle: float = float("inf"),
                             ) -> tuple[OptimizeResult, dict[str, Any]]:
    """:class:`MultistartLeastSquares` over a residual function and every start given
    (lazily: a generator is read one start at a time), with absolute ``accept`` and
    ``settle`` fitness levels, ``max_evals`` and ``max_seconds`` as the budget.
    ``fitness(X) -> (m,)``, if given, is ``||r||^2`` computed more cheaply for the polish.
    Returns ``(result, info)``: ``info`` holds ``starts`` (how many were run), ``x_raw,
    f_raw`` (the best before the polish), ``polish_evaluations`` and ``polish_s``."""
    if isinstance(starts, (list, tuple)) and not starts:
        raise ValueError("multistart_least_squares needs at least one start")
    solver = MultistartLeastSquares(restarts=sys.maxsize - 1, accept_ratio=accept,
                                    settle_ratio=settle, diff_steps=tuple(diff_steps),
                                    polish_evaluations=polish_evals, min_gain=min_gain)
    term = _Limits(max_evals, max_seconds)
    problem = _Given(residuals, starts, as_bounds(bounds), fitness)
    state = solver.init(problem, term, 0)
    while state.reason is None:
        state = solver.step(problem, state, callback)
    res = solver.result(state)
    return (OptimizeResult(x=res.x, fun=res.fun, nfev=res.nfev, nit=res.nit, history=res.history,
                           reason=res.reason, elapsed_s=res.elapsed_s, algorithm="lsq"),
            {"starts": res.starts, "x_raw": res.x_raw, "f_raw": res.fun_raw,
             "polish_evaluations": res.polish_evaluations, "polish_s": res.polish_s})


@dataclass(frozen=True)
class _Limits:
    """An evaluation and a wall-clock budget as one termination's ``remaining``."""

    evaluations: float
    seconds: float

    def remaining(self, nfev: int, elapsed_s: float) -> tuple[float, float]:
        return self.evaluations - nfev, self.seconds - elapsed_s
