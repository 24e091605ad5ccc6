"""Steppable solvers over a problem: one protocol for everything that searches.

The ask/tell optimizers (:mod:`emaphm.optim.de`, ``pso``, ``gwo``, the baselines) see a
box and a batch objective. A *solver* drives a whole search over a *problem*, as in
pymoo's ``minimize(problem, algorithm, termination, seed)``, and is stopped by the same
:class:`~emaphm.optim.base.Termination` objects as the optimizers. Like the optimizers,
solvers know nothing about actuators.

A **problem** is any object with (shapes as everywhere in :mod:`emaphm.optim`)::

    bounds            Bounds or (lo, hi)            the search box
    evaluate(X)       (n, n_var) -> (n,)            batch fitness; non-finite reads as worst

and, for the solvers that use them::

    residuals(X)      (n, n_var) -> (n, m)          rows whose sum of squares is the fitness
    starts()          iterable of (n_var,) points   where a local solver starts, in order
    sample_size       int                           points that sample() evaluates
    sample(seed)      -> (X (n, n_var), y (n,))     screened candidates for further starts
    fitness_floor     float                         the fitness a perfect fit reaches
                                                    (the noise); 0 where unknown

A **solver** is a frozen configuration with::

    state = solver.init(problem, termination, seed)     # termination may be None
    state = solver.step(problem, state, callback)       # one unit of work
    solver.result(state) -> SolverResult                # once state.reason is not None

:func:`solve` is nothing but that loop. ``callback(state)``, where given, is called with
the progress (an object with ``best_f``, ``nfev``, ``nit``) and a true return stops the
search with reason ``"callback"``.

Solvers here: :class:`Metaheuristic` (an ask/tell optimizer, then a compass-search
polish, restarted with spawned seeds while the fit stays far above the problem's
``fitness_floor``), :class:`CallableSolver` (a plain function
``f(objective, bounds, rng) -> x``, e.g. a user's own optimizer) and
:class:`emaphm.optim.lsq.MultistartLeastSquares`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, fields, replace
from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np

from .base import (OptimizeResult, Optimizer, Termination, as_bounds, check_int, remaining,
                   sanitize_fitness, _as_generator, _check_optimizer)
from .local import compass_search
from ..seeds import check_seed

__all__ = ["Solver", "SolverResult", "solve", "Metaheuristic", "MetaheuristicState",
           "CallableSolver", "restart_seeds", "optimizer_options"]


def restart_seeds(seed: int, n: int) -> list[int]:
    """Seeds of ``n`` restarts, spawned from ``seed`` (independent of how many follow)."""
    return [int(s.generate_state(1)[0] % 2**31) for s in np.random.SeedSequence([seed, 1]).spawn(n)]


def optimizer_options(optimizer: Any) -> dict[str, Any]:
    """The settings of an optimizer configuration that differ from its class defaults
    (``PSO(pop_size=20)`` -> ``{"pop_size": 20}``); empty for an object that is not a
    dataclass."""
    try:
        fs = fields(optimizer)
    except TypeError:
        return {}
    out = {}
    for f in fs:
        if not f.init or f.name.startswith("_"):
            continue
        value = getattr(optimizer, f.name)
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = dataclasses.MISSING
        try:
            same = bool(np.all(value == default))
        except Exception:        # noqa: BLE001 - an exotic value: report it
            same = False
        if not same:
            out[f.name] = value
    return out


@runtime_checkable
class Solver(Protocol):
    """What every solver provides (see the module docstring)."""

    name: str

    def init(self, problem: Any, termination: Termination | None, seed: int) -> Any: ...

    def step(self, problem: Any, state: Any, callback: Callable[[Any], Any] | None = None) -> Any: ...

    def result(self, state: Any) -> "SolverResult": ...


@dataclass(frozen=True, eq=False)
class SolverResult:
    """The outcome of :func:`solve` (plain data).

    ``x, fun``: the best point and its fitness; ``nfev``: every evaluation the solver
    made (screened samples and the polish included); ``nit``, ``history`` and ``reason``:
    those of the best run (``history`` the best fitness after each iteration, the
    polish's polls appended); ``x_raw, fun_raw``: the best point before the polish;
    ``starts``: runs or starts made; ``polish_evaluations``: the best run's polish;
    ``polish_s``: seconds of every polish; ``run_evaluations``: the best run's
    evaluations with its polish (for the least-squares solver: every pass and the
    polish, without the screened sample).
    """

    x: np.ndarray
    fun: float
    nfev: int
    nit: int
    history: np.ndarray
    reason: str
    elapsed_s: float
    algorithm: str
    x_raw: np.ndarray
    fun_raw: float
    starts: int = 1
    polish_evaluations: int = 0
    polish_s: float = 0.0
    run_evaluations: int = 0


def solve(problem: Any, solver: Any, termination: Termination | None = None, *, seed: int,
          callback: Callable[[Any], Any] | None = None) -> SolverResult:
    """Run ``solver`` on ``problem`` until it finishes or ``termination`` stops it."""
    if termination is not None and not isinstance(termination, Termination):
        raise ValueError("termination must be a termination object such as MaxEvaluations(5000), "
                         f"got {type(termination).__name__}")
    if callback is not None and not callable(callback):
        raise ValueError(f"callback must be callable, got {type(callback).__name__}")
    state = solver.init(problem, termination, check_seed(seed))
    while state.reason is None:
        state = solver.step(problem, state, callback)
    return solver.result(state)


# ----------------------------------------------------------------------------- metaheuristic


@dataclass(frozen=True, eq=False)
class _Run:
    """One finished run of a metaheuristic and its polish (problem coordinates)."""

    res: OptimizeResult
    x: np.ndarray
    fun: float
    history: np.ndarray
    polish_evaluations: int
    polish_s: float


@dataclass(frozen=True, eq=False)
class MetaheuristicState:
    """Progress of a :class:`Metaheuristic`: the current run's optimizer state ``opt`` (what
    a callback receives) and the finished ``runs``."""

    termination: Termination
    seeds: tuple[int, ...]
    opt: Any
    run_t0: float
    t0: float
    runs: tuple[_Run, ...] = ()
    best: int = -1
    reason: str | None = None


@dataclass(frozen=True)
class Metaheuristic:
    """An ask/tell optimizer run to its termination, polished, restarted if far off.

    ==================  =================================================================
    setting             meaning
    ==================  =================================================================
    optimizer           an :class:`~emaphm.optim.base.Optimizer` (``DE()``, ``PSO()``, ...)
    polish              refine the run's best point by :func:`~emaphm.optim.local.compass_search`
                        (step 0.05 down to 1e-4), charged to an evaluation or wall-clock
                        termination and skipped when too little is left or a callback
                        stopped the run
    polish_evaluations  most evaluations one polish may spend
    restarts            further runs, with seeds spawned from the seed (:func:`restart_seeds`),
                        made while the best fit exceeds ``restart_ratio`` times the
                        problem's ``fitness_floor`` (a wrong basin); each run gets the
                        whole termination
    restart_ratio       see ``restarts`` (``inf``: never)
    ==================  =================================================================

    Each :meth:`step` is one ask/tell iteration; the one that ends a run also polishes it
    and starts the next. The termination (default: the optimizer's own) applies to each
    run, as to :func:`emaphm.optim.minimize`.
    """

    optimizer: Optimizer
    polish: bool = True
    restarts: int = 0
    restart_ratio: float = math.inf
    polish_evaluations: int = 2000
    kind = "population"

    def __post_init__(self) -> None:
        _check_optimizer(self.optimizer)
        check_int("Metaheuristic", "restarts", self.restarts, 0)
        check_int("Metaheuristic", "polish_evaluations", self.polish_evaluations, 1)
        if isinstance(self.polish, bool) is False:
            raise ValueError(f"Metaheuristic: polish must be True or False, got {self.polish!r}")
        if not (isinstance(self.restart_ratio, (int, float)) and self.restart_ratio > 1):
            raise ValueError(f"Metaheuristic: restart_ratio must be a number > 1, got "
                             f"{self.restart_ratio!r}")

    @property
    def name(self) -> str:
        return self.optimizer.name

    def _start(self, problem: Any, termination: Termination, seed: int, t0: float,
               seeds: tuple[int, ...], runs: tuple = (), best: int = -1) -> MetaheuristicState:
        opt = self.optimizer.init(as_bounds(problem.bounds), _as_generator(seed))
        state = MetaheuristicState(termination, seeds, opt, time.perf_counter(), t0, runs, best)
        reason = termination.check(opt, 0.0)     # as resume(): a finished budget stops at once
        return self._finish_run(problem, state, reason) if reason is not None else state

    def init(self, problem: Any, termination: Termination | None, seed: int) -> MetaheuristicState:
        if termination is None:
            termination = self.optimizer.default_termination()
        seeds = (seed, *restart_seeds(seed, self.restarts))
        return self._start(problem, termination, seed, time.perf_counter(), seeds)

    def step(self, problem: Any, state: MetaheuristicState,
             callback: Callable[[Any], Any] | None = None) -> MetaheuristicState:
        X = self.optimizer.ask(state.opt)
        y = sanitize_fitness(problem.evaluate(X.copy()), X.shape[0])
        opt = self.optimizer.tell(state.opt, X, y)
        state = replace(state, opt=opt)
        if callback is not None and callback(opt):
            return self._finish_run(problem, state, "callback")
        reason = state.termination.check(opt, time.perf_counter() - state.run_t0)
        return state if reason is None else self._finish_run(problem, state, reason)

    def _finish_run(self, problem: Any, state: MetaheuristicState, reason: str) -> MetaheuristicState:
        o = state.opt
        res = OptimizeResult(x=np.array(o.best_x, dtype=np.float64), fun=float(o.best_f),
                             nfev=int(o.nfev), nit=int(o.nit),
                             history=np.array(o.history, dtype=np.float64), reason=reason,
                             elapsed_s=time.perf_counter() - state.run_t0,
                             algorithm=self.optimizer.name)
        run = self._polish(problem, res, state)
        runs = state.runs + (run,)
        best = len(runs) - 1 if state.best < 0 or run.fun < runs[state.best].fun else state.best
        floor = float(getattr(problem, "fitness_floor", 0.0) or 0.0)
        limit = self.restart_ratio * floor if floor > 0 else math.inf
        if len(runs) < len(state.seeds) and runs[best].fun > limit and reason != "callback":
            return self._start(problem, state.termination, state.seeds[len(runs)], state.t0,
                               state.seeds, runs, best)
        return replace(state, runs=runs, best=best, opt=None, reason=runs[best].res.reason)

    def _polish(self, problem: Any, res: OptimizeResult, state: MetaheuristicState) -> _Run:
        history = np.asarray(res.history, dtype=float)
        evals, seconds = remaining(state.termination, res.nfev, time.perf_counter() - state.t0)
        evals = min(self.polish_evaluations, evals)
        if self.polish and np.isfinite(res.fun) and res.reason != "callback" \
                and evals >= 2 * res.x.size and seconds > 0:
            pol = compass_search(problem.evaluate, res.x, problem.bounds, f0=res.fun,
                                 max_evals=int(evals), max_seconds=seconds)
            return _Run(res, pol.x, float(pol.fun), np.concatenate([history, pol.history[1:]]),
                        pol.nfev, pol.elapsed_s)
        return _Run(res, res.x, float(res.fun), history, 0, 0.0)

    def result(self, state: MetaheuristicState) -> SolverResult:
        b = state.runs[state.best]
        return SolverResult(
            x=b.x, fun=b.fun, nfev=sum(r.res.nfev + r.polish_evaluations for r in state.runs),
            nit=b.res.nit, history=b.history, reason=b.res.reason,
            elapsed_s=time.perf_counter() - state.t0, algorithm=self.name, x_raw=b.res.x,
            fun_raw=float(b.res.fun), starts=len(state.runs),
            polish_evaluations=b.polish_evaluations,
            polish_s=sum(r.polish_s for r in state.runs),
            run_evaluations=int(b.res.nfev) + b.polish_evaluations)


# ----------------------------------------------------------------------------- a function


class _Spent(Exception):
    """Raised inside a :class:`CallableSolver`'s objective when the budget is spent."""


@dataclass(frozen=True, eq=False)
class CallableState:
    """Progress of a :class:`CallableSolver`: nothing until its one step has run."""

    termination: Termination | None
    seed: int
    t0: float
    result: SolverResult | None = None
    reason: str | None = None


@dataclass(frozen=True)
class CallableSolver:
    """A plain function as a solver: ``fn(objective, bounds, rng) -> x``.

    ``objective(X) -> y`` is the problem's batch fitness ((n, n_var) -> (n,)), ``bounds``
    the pair ``(lo, hi)`` and ``rng`` a :class:`numpy.random.Generator` seeded from the
    seed. One :meth:`step` runs the function. The result is the best point it evaluated
    or returned (whichever fits better). An evaluation or wall-clock termination is
    enforced: once spent, the objective stops the function, and the best point so far is
    the result (reason ``"max_evaluations"`` or ``"wall_clock"``); otherwise the reason
    is ``"returned"``. ``name`` defaults to the function's name.
    """

    fn: Callable[..., Any]
    name: str = ""
    kind = "population"

    def __post_init__(self) -> None:
        if not callable(self.fn):
            raise ValueError(f"CallableSolver needs a function fn(objective, bounds, rng) -> x, "
                             f"got {type(self.fn).__name__}")
        object.__setattr__(self, "name", self.name or getattr(self.fn, "__name__", "callable"))

    def init(self, problem: Any, termination: Termination | None, seed: int) -> CallableState:
        return CallableState(termination, seed, time.perf_counter())

    def step(self, problem: Any, state: CallableState,
             callback: Callable[[Any], Any] | None = None) -> CallableState:
        st, termination = state, state.termination
        b = as_bounds(problem.bounds)
        best = {"x": b.from_normalized(np.full(b.n_var, 0.5)), "f": math.inf, "nfev": 0}

        def objective(X: Any) -> np.ndarray:
            X = np.atleast_2d(np.asarray(X, dtype=float))
            if X.ndim != 2 or X.shape[1] != b.n_var:
                raise ValueError(f"the objective takes points of shape (n, {b.n_var}), got {X.shape}")
            evals, seconds = remaining(termination, best["nfev"], time.perf_counter() - st.t0)
            if X.shape[0] > evals or seconds <= 0:
                raise _Spent("max_evaluations" if seconds > 0 else "wall_clock")
            y = sanitize_fitness(problem.evaluate(np.clip(X, b.lo, b.hi)), X.shape[0])
            best["nfev"] += X.shape[0]
            i = int(np.argmin(y))
            if y[i] < best["f"]:
                best["x"], best["f"] = np.clip(X[i], b.lo, b.hi), float(y[i])
            if callback is not None and callback(_Progress(best["f"], best["nfev"])):
                raise _Spent("callback")
            return y

        reason = "returned"
        try:
            x = self.fn(objective, (b.lo.copy(), b.hi.copy()), np.random.default_rng(st.seed))
            x = np.clip(np.asarray(x, dtype=float).reshape(b.n_var), b.lo, b.hi)
            objective(x[None, :])
        except _Spent as exc:
            reason = str(exc)
        res = SolverResult(x=np.asarray(best["x"]), fun=best["f"], nfev=best["nfev"],
                           nit=1, history=np.array([best["f"]]), reason=reason,
                           elapsed_s=time.perf_counter() - st.t0, algorithm=self.name,
                           x_raw=np.asarray(best["x"]), fun_raw=best["f"],
                           run_evaluations=best["nfev"])
        return replace(st, result=res, reason=reason)

    def result(self, state: CallableState) -> SolverResult:
        return state.result


@dataclass(frozen=True)
class _Progress:
    """What a :class:`CallableSolver` tells a callback after each evaluation."""

    best_f: float
    nfev: int
    nit: int = 1
