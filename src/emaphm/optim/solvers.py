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

from .base import (AnyOf, MaxEvaluations, OptimizeResult, Optimizer, Termination, WallClock,
                   as_bounds, check_int, remaining, sanitize_fitness, _as_generator,
                   _check_optimizer)
from .local import compass_search
from ..seeds import check_seed

__all__ = ["Solver", "SolverResult", "solve", "Metaheuristic", "MetaheuristicState",
           "CallableSolver", "restart_seeds", "optimizer_options", "BudgetPlan", "plan_budget",
           "POLISH_SHARE"]

#: Share of each run's budget (evaluations or seconds) a budgeted run holds back for its
#: polish (at most the solver's ``polish_evaluations``): the compass search needs 150-500
#: evaluations where a metaheuristic's run takes thousands. A tenth: on a budget of 3000
#: that is 300 evaluations, about 19 polls of the 16 points of k's eight components.
POLISH_SHARE = 0.1


@dataclass(frozen=True)
class BudgetPlan:
    """How a termination's budget is spent by each run of a solver: ``evals`` evaluations
    and ``seconds`` of wall clock a run (``inf``: no such limit), of which ``polish_evals``
    and ``polish_seconds`` are held back for its polish. Built by :func:`plan_budget`."""

    evals: float
    seconds: float
    polish_evals: int
    polish_seconds: float

    @property
    def limited(self) -> bool:
        return math.isfinite(self.evals) or math.isfinite(self.seconds)

    def run_termination(self, termination: Termination) -> Termination:
        """``termination`` less the polish's share (itself where it sets no budget of
        evaluations or seconds, or no polish is made)."""
        terms = [termination]
        if self.polish_evals:
            terms.append(MaxEvaluations(max(1, int(self.evals) - self.polish_evals)))
        if self.polish_seconds:
            terms.append(WallClock(max(1e-3, self.seconds - self.polish_seconds)))
        return terms[0] if len(terms) == 1 else AnyOf(*terms)

    def polish_left(self, run_evals: int, run_s: float) -> tuple[float, float]:
        """``(evaluations, seconds)`` the polish of a run that spent ``run_evals`` and
        ``run_s`` may spend: the rest of the run's budget."""
        return self.evals - run_evals, self.seconds - run_s


def plan_budget(termination: Any, polish: bool, polish_evaluations: int) -> BudgetPlan:
    """The :class:`BudgetPlan` of each run under ``termination``: its evaluations and
    seconds (:func:`~emaphm.optim.base.remaining`), of which :data:`POLISH_SHARE` (at most
    ``polish_evaluations``) is held back for the polish."""
    e, sec = remaining(termination, 0, 0.0)
    pe = int(min(polish_evaluations, math.floor(POLISH_SHARE * e))) if polish and math.isfinite(e) else 0
    ps = POLISH_SHARE * sec if polish and math.isfinite(sec) else 0.0
    return BudgetPlan(e, sec, pe, ps)


def _skipped_polish(fun: float, reason: str, evals: float, seconds: float, n_var: int) -> str:
    """Why a polish was not made ("" where nothing stood in its way)."""
    if reason == "callback":
        return "the callback stopped the search"
    if not np.isfinite(fun):
        return "every candidate diverged"
    if evals < 2 * n_var:
        return (f"the budget left {max(int(evals), 0)} evaluations, fewer than one poll "
                f"({2 * n_var}); give a larger budget")
    if seconds <= 0:
        return "the wall-clock budget was spent; give a longer one"
    return ""


def _skipped_restarts(fun: float, floor: float, ratio: float, restarts: int, limited: bool) -> str:
    """Why no further run was made although the fit stayed far above the noise floor."""
    if not (floor > 0 and fun > ratio * floor):
        return ""
    if restarts == 0:
        return (f"the best fit is {fun / floor:.1f}x the noise floor (a restart is due above "
                f"{ratio:.3g}x) and no restart was allowed"
                + ("; under a budget the restarts default to 0 (a budget caps the search): "
                   "give restarts=N for up to N further runs, each with the whole budget"
                   if limited else ""))
    return (f"the best fit is {fun / floor:.1f}x the noise floor after the {restarts} restart(s) "
            "allowed")


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
    polish, without the screened sample); ``skipped``: what the solver promises and did
    not do, with the reason (``{"polish": ..., "restarts": ...}``).
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
    skipped: dict = dataclasses.field(default_factory=dict)


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
    polish_skipped: str = ""


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
    plan: BudgetPlan | None = None
    run_termination: Termination | None = None
    floor: float = 0.0


@dataclass(frozen=True)
class Metaheuristic:
    """An ask/tell optimizer run to its termination, polished, restarted if far off.

    ==================  =================================================================
    setting             meaning
    ==================  =================================================================
    optimizer           an :class:`~emaphm.optim.base.Optimizer` (``DE()``, ``PSO()``, ...)
    polish              refine the run's best point by :func:`~emaphm.optim.local.compass_search`
                        (step 0.05 down to 1e-4); skipped when a callback stopped the run
                        (the result's ``skipped`` says why)
    polish_evaluations  most evaluations one polish may spend
    restarts            further runs, with seeds spawned from the seed (:func:`restart_seeds`),
                        made while the best fit exceeds ``restart_ratio`` times the
                        problem's ``fitness_floor`` (a wrong basin)
    restart_ratio       see ``restarts`` (``inf``: never)
    label               the name the solver goes by (default the optimizer's ``name``): a
                        registered optimizer's name (:func:`emaphm.optim.register`)
    ==================  =================================================================

    Each :meth:`step` is one ask/tell iteration; the one that ends a run also polishes it
    and starts the next. The termination (default: the optimizer's own) applies to each
    run, as to :func:`emaphm.optim.minimize`; a budget of evaluations or seconds holds
    :data:`POLISH_SHARE` of it (at most ``polish_evaluations``) back for the run's polish
    (:func:`plan_budget`), so that a budget is never spent before the polish. Where the
    fit stays far above the floor with no restart left, or the polish could not be made,
    the result's ``skipped`` says why.
    """

    optimizer: Optimizer
    polish: bool = True
    restarts: int = 0
    restart_ratio: float = math.inf
    polish_evaluations: int = 2000
    label: str = ""
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
        return self.label or self.optimizer.name

    def _start(self, problem: Any, state: MetaheuristicState, seed: int) -> MetaheuristicState:
        opt = self.optimizer.init(as_bounds(problem.bounds), _as_generator(seed))
        state = replace(state, opt=opt, run_t0=time.perf_counter())
        reason = state.run_termination.check(opt, 0.0)  # as resume(): a spent budget stops at once
        return self._finish_run(problem, state, reason) if reason is not None else state

    def init(self, problem: Any, termination: Termination | None, seed: int) -> MetaheuristicState:
        if termination is None:
            termination = self.optimizer.default_termination()
        seeds = (seed, *restart_seeds(seed, self.restarts))
        plan = plan_budget(termination, self.polish, self.polish_evaluations)
        t0 = time.perf_counter()
        state = MetaheuristicState(termination, seeds, None, t0, t0, plan=plan,
                                   run_termination=plan.run_termination(termination),
                                   floor=float(getattr(problem, "fitness_floor", 0.0) or 0.0))
        return self._start(problem, state, seed)

    def step(self, problem: Any, state: MetaheuristicState,
             callback: Callable[[Any], Any] | None = None) -> MetaheuristicState:
        X = self.optimizer.ask(state.opt)
        y = sanitize_fitness(problem.evaluate(X.copy()), X.shape[0])
        opt = self.optimizer.tell(state.opt, X, y)
        state = replace(state, opt=opt)
        if callback is not None and callback(opt):
            return self._finish_run(problem, state, "callback")
        reason = state.run_termination.check(opt, time.perf_counter() - state.run_t0)
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
            return self._start(problem, replace(state, runs=runs, best=best),
                               state.seeds[len(runs)])
        return replace(state, runs=runs, best=best, opt=None, reason=runs[best].res.reason)

    def _polish(self, problem: Any, res: OptimizeResult, state: MetaheuristicState) -> _Run:
        history = np.asarray(res.history, dtype=float)
        evals, seconds = state.plan.polish_left(res.nfev, time.perf_counter() - state.run_t0)
        evals = min(self.polish_evaluations, evals)
        if not self.polish:
            return _Run(res, res.x, float(res.fun), history, 0, 0.0)
        why = _skipped_polish(res.fun, res.reason, evals, seconds, res.x.size)
        if not why:
            pol = compass_search(problem.evaluate, res.x, problem.bounds, f0=res.fun,
                                 max_evals=int(evals), max_seconds=seconds)
            return _Run(res, pol.x, float(pol.fun), np.concatenate([history, pol.history[1:]]),
                        pol.nfev, pol.elapsed_s)
        return _Run(res, res.x, float(res.fun), history, 0, 0.0, why)

    def result(self, state: MetaheuristicState) -> SolverResult:
        b = state.runs[state.best]
        return SolverResult(
            x=b.x, fun=b.fun, nfev=sum(r.res.nfev + r.polish_evaluations for r in state.runs),
            nit=b.res.nit, history=b.history, reason=b.res.reason,
            elapsed_s=time.perf_counter() - state.t0, algorithm=self.name, x_raw=b.res.x,
            fun_raw=float(b.res.fun), starts=len(state.runs),
            polish_evaluations=b.polish_evaluations,
            polish_s=sum(r.polish_s for r in state.runs),
            run_evaluations=int(b.res.nfev) + b.polish_evaluations,
            skipped=self._skipped(state))

    def _skipped(self, state: MetaheuristicState) -> dict[str, str]:
        b = state.runs[state.best]
        out = {"polish": b.polish_skipped} if b.polish_skipped else {}
        why = "" if b.res.reason == "callback" else _skipped_restarts(
            b.fun, state.floor, self.restart_ratio, self.restarts, state.plan.limited)
        return {**out, "restarts": why} if why else out


# ----------------------------------------------------------------------------- a function


class _Spent(Exception):
    """Raised inside a :class:`CallableSolver`'s objective when the budget is spent."""


@dataclass(frozen=True, eq=False)
class CallableState:
    """Progress of a :class:`CallableSolver`: the runs made so far (each a :class:`_Run`)."""

    termination: Termination | None
    seed: int
    t0: float
    seeds: tuple[int, ...] = ()
    plan: BudgetPlan | None = None
    runs: tuple[_Run, ...] = ()
    best: int = -1
    floor: float = 0.0
    result: SolverResult | None = None
    reason: str | None = None


@dataclass(frozen=True)
class CallableSolver:
    """A plain function as a solver: ``fn(objective, bounds, rng) -> x``, polished and
    restarted as :class:`Metaheuristic` polishes and restarts an optimizer.

    ``objective(X) -> y`` is the problem's batch fitness ((n, n_var) -> (n,)), ``bounds``
    the pair ``(lo, hi)`` and ``rng`` a :class:`numpy.random.Generator` seeded from the
    seed (a restart's from :func:`restart_seeds`). One :meth:`step` is one run of the
    function and its polish. A run's result is the best point the function evaluated or
    returned (whichever fits better). An evaluation or wall-clock termination is enforced:
    once a run's share is spent, the objective stops the function and the best point so
    far is the run's result (reason ``"max_evaluations"`` or ``"wall_clock"``; otherwise
    ``"returned"``); each run gets the whole budget, less the polish's share
    (:func:`plan_budget`). ``polish``, ``polish_evaluations``, ``restarts`` and
    ``restart_ratio`` as in :class:`Metaheuristic` (default: polished, no restart);
    ``name`` defaults to the function's name.
    """

    fn: Callable[..., Any]
    name: str = ""
    polish: bool = True
    restarts: int = 0
    restart_ratio: float = math.inf
    polish_evaluations: int = 2000
    kind = "population"

    def __post_init__(self) -> None:
        if not callable(self.fn):
            raise ValueError(f"CallableSolver needs a function fn(objective, bounds, rng) -> x, "
                             f"got {type(self.fn).__name__}")
        check_int("CallableSolver", "restarts", self.restarts, 0)
        check_int("CallableSolver", "polish_evaluations", self.polish_evaluations, 1)
        if not isinstance(self.polish, bool):
            raise ValueError(f"CallableSolver: polish must be True or False, got {self.polish!r}")
        if not (isinstance(self.restart_ratio, (int, float)) and self.restart_ratio > 1):
            raise ValueError(f"CallableSolver: restart_ratio must be a number > 1, got "
                             f"{self.restart_ratio!r}")
        object.__setattr__(self, "name", self.name or getattr(self.fn, "__name__", "callable"))

    def init(self, problem: Any, termination: Termination | None, seed: int) -> CallableState:
        seeds = (seed, *restart_seeds(seed, self.restarts))
        return CallableState(termination, seed, time.perf_counter(), seeds,
                             plan_budget(termination, self.polish, self.polish_evaluations),
                             floor=float(getattr(problem, "fitness_floor", 0.0) or 0.0))

    def step(self, problem: Any, state: CallableState,
             callback: Callable[[Any], Any] | None = None) -> CallableState:
        i = len(state.runs)
        res = self._call(problem, state, state.seeds[i], callback)
        run = self._polish(problem, res, state)
        runs = state.runs + (run,)
        best = i if state.best < 0 or run.fun < runs[state.best].fun else state.best
        limit = self.restart_ratio * state.floor if state.floor > 0 else math.inf
        state = replace(state, runs=runs, best=best)
        if len(runs) < len(state.seeds) and run.res.reason != "callback" and runs[best].fun > limit:
            return state
        return replace(state, result=self._result(state), reason=runs[best].res.reason)

    def _call(self, problem: Any, state: CallableState, seed: int,
              callback: Callable[[Any], Any] | None) -> OptimizeResult:
        """One run of the function, stopped when its share of the budget is spent."""
        b = as_bounds(problem.bounds)
        plan, t_run = state.plan, time.perf_counter()
        done = sum(r.res.nfev + r.polish_evaluations for r in state.runs)
        share = plan.evals - plan.polish_evals
        seconds = plan.seconds - plan.polish_seconds
        best = {"x": b.from_normalized(np.full(b.n_var, 0.5)), "f": math.inf, "nfev": 0}

        def objective(X: Any) -> np.ndarray:
            X = np.atleast_2d(np.asarray(X, dtype=float))
            if X.ndim != 2 or X.shape[1] != b.n_var:
                raise ValueError(f"the objective takes points of shape (n, {b.n_var}), got {X.shape}")
            evals = share - best["nfev"]
            left = seconds - (time.perf_counter() - t_run)
            if X.shape[0] > evals or left <= 0:
                raise _Spent("max_evaluations" if left > 0 else "wall_clock")
            y = sanitize_fitness(problem.evaluate(np.clip(X, b.lo, b.hi)), X.shape[0])
            best["nfev"] += X.shape[0]
            i = int(np.argmin(y))
            if y[i] < best["f"]:
                best["x"], best["f"] = np.clip(X[i], b.lo, b.hi), float(y[i])
            if callback is not None and callback(_Progress(best["f"], done + best["nfev"])):
                raise _Spent("callback")
            return y

        reason = "returned"
        try:
            x = self.fn(objective, (b.lo.copy(), b.hi.copy()), np.random.default_rng(seed))
            x = np.clip(np.asarray(x, dtype=float).reshape(b.n_var), b.lo, b.hi)
            objective(x[None, :])
        except _Spent as exc:
            reason = str(exc)
        return OptimizeResult(x=np.asarray(best["x"]), fun=best["f"], nfev=best["nfev"], nit=1,
                              history=np.array([best["f"]]), reason=reason,
                              elapsed_s=time.perf_counter() - t_run, algorithm=self.name)

    def _polish(self, problem: Any, res: OptimizeResult, state: CallableState) -> _Run:
        """The run's polish (:func:`~emaphm.optim.local.compass_search`), as a
        :class:`Metaheuristic` polishes its runs."""
        history = np.asarray(res.history, dtype=float)
        if not self.polish:
            return _Run(res, res.x, float(res.fun), history, 0, 0.0)
        evals, seconds = state.plan.polish_left(res.nfev, res.elapsed_s)
        evals = min(self.polish_evaluations, evals)
        why = _skipped_polish(res.fun, res.reason, evals, seconds, res.x.size)
        if why:
            return _Run(res, res.x, float(res.fun), history, 0, 0.0, why)
        pol = compass_search(problem.evaluate, res.x, problem.bounds, f0=res.fun,
                             max_evals=int(evals), max_seconds=seconds)
        return _Run(res, pol.x, float(pol.fun), np.concatenate([history, pol.history[1:]]),
                    pol.nfev, pol.elapsed_s)

    def _result(self, state: CallableState) -> SolverResult:
        b = state.runs[state.best]
        skipped = {"polish": b.polish_skipped} if b.polish_skipped else {}
        why = "" if b.res.reason == "callback" else _skipped_restarts(
            b.fun, state.floor, self.restart_ratio, self.restarts, state.plan.limited)
        if why:
            skipped["restarts"] = why
        return SolverResult(
            x=np.asarray(b.x), fun=float(b.fun),
            nfev=sum(r.res.nfev + r.polish_evaluations for r in state.runs), nit=len(state.runs),
            history=b.history, reason=b.res.reason, elapsed_s=time.perf_counter() - state.t0,
            algorithm=self.name, x_raw=np.asarray(b.res.x), fun_raw=float(b.res.fun),
            starts=len(state.runs), polish_evaluations=b.polish_evaluations,
            polish_s=sum(r.polish_s for r in state.runs),
            run_evaluations=int(b.res.nfev) + b.polish_evaluations, skipped=skipped)

    def result(self, state: CallableState) -> SolverResult:
        return state.result


@dataclass(frozen=True)
class _Progress:
    """What a :class:`CallableSolver` tells a callback after each evaluation."""

    best_f: float
    nfev: int
    nit: int = 1
