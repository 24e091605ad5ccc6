"""Well-kept baselines behind the ask/tell protocol of :mod:`emaphm.optim`: scipy's
vectorised differential evolution and CMA-ES from the ``cma`` package.

They let a campaign show how the paper's three algorithms (our own DE, PSO and GWO)
compare with mature, widely used implementations, with the same problem, the same
budget rules and the same bookkeeping (``nfev``, ``nit``, ``history``).

==========  ================================================================================
name        what runs
==========  ================================================================================
scipy-de    :class:`ScipyDE`: ``scipy.optimize.differential_evolution`` with
            ``vectorized=True, updating='deferred', polish=False`` (one batch per
            generation), driven one generation at a time
cmaes       :class:`CMAES`: ``cma.CMAEvolutionStrategy`` (Hansen) in the normalised box with
            ``bounds=[0, 1]``, its own ask/tell
==========  ================================================================================

Both are full ask/tell optimizers (not "minimize-only"), so :func:`emaphm.identify.identify`,
:func:`emaphm.optim.minimize`, checkpoints and campaigns reach them like any other, by
name through :func:`emaphm.optim.get_optimizer` (registry :data:`emaphm.optim.BASELINES`,
beside the paper's three in :data:`emaphm.optim.ALGORITHMS`).

How the scipy adapter works
---------------------------
scipy's solver calls the objective itself, from inside ``next(solver)`` (one
generation). The adapter inverts that control without threads: the state holds the
solver at the start of a generation plus the fitness batches already told in that
generation. Asking runs the generation with an objective that serves the told batches
and *raises* at the first batch it does not know, capturing the points scipy wants
evaluated, and then undoes the interrupted generation (a checkpoint of the solver's
attributes and of its random stream); ``tell`` runs it with one more batch and, when
the generation completes, asks the next one. The solver is owned by the newest state
and advanced in place (copy on write, :class:`_Owned`): an older state is rebuilt by
replaying the told batches from a snapshot, so ``tell`` never changes its input state.
The run is bit-for-bit the one
``differential_evolution(..., init=<the same initial population>, rng=<the same
Generator>, vectorized=True, updating='deferred', polish=False)`` makes (tested), apart
from the stopping rule, which is emaphm's.

Boundary handling is each library's own, not emaphm's clipping: scipy re-draws a
component that leaves the box uniformly inside it, and cma maps its samples into the
box by a smooth transformation. Neither lands exactly on a face, so a component whose
true value is the bound (``k_i = 0``) is approached, not hit (the polish of
:func:`~emaphm.identify.identify` closes that gap).

Dependencies
------------
The module imports neither scipy's solver nor cma at import time; ``init`` does. It
touches two private details of scipy (checked from scipy 1.13 to 1.17, :data:`SCIPY_CHECKED`,
with a warning outside them and a clear error where they are gone,
:func:`scipy_private`; the ``seed=`` keyword of scipy < 1.15 is handled): the solver class
``scipy.optimize._differentialevolution.DifferentialEvolutionSolver``, whose
``next(solver)`` runs one generation, and its ``_mapwrapper`` attribute, replaced by a
picklable equivalent so that states pickle. Should a scipy release change them, the
replay check fails loudly (``RuntimeError``) rather than running a different algorithm.
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
import threading
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .base import (
    Bounds,
    MaxIterations,
    StallTolerance,
    Termination,
    advance,
    as_bounds,
    check_int,
    check_real,
    check_told,
    child_rng,
    fork_rng,
    frozen,
    start,
)

__all__ = ["BASELINES", "CMAES", "CMAESState", "ScipyDE", "ScipyDEState"]


# --------------------------------------------------------------------------- engine ownership


#: A state keeps a full copy of its engine (a snapshot) every this many ``tell`` calls, so
#: that rebuilding an old state replays at most this many steps (and a run keeps at most
#: this many recipes alive).
SNAPSHOT_EVERY = 32


class _Owned:
    """The mutable engine of one state (cma's strategy, scipy's solver), copy on write.

    The third-party engines change in place, while states are values (``tell`` leaves
    its input state alone). Copying the engine on every ``tell`` kept that promise at
    the price of a deep copy per iteration (about 1.3 ms for cma, more than its own
    tell and ask). Instead, the engine is *owned*: the newest state holds it *live*,
    and ``tell`` takes it, advances it in place and hands it to the new state. The
    state told from keeps a *recipe*: its parent and the step (the told batch) that
    led from the parent's engine to its own. Reusing such an old state (telling it
    again, reading ``es``/``solver``, pickling, ``copy.deepcopy``) rebuilds its engine
    from the nearest snapshot by replaying the recorded steps: the same operations on
    the same engine as the original run, so the result is the one copying gave, bit
    for bit. A state whose engine has no recipe (the first state of a run, an
    unpickled one, and every :data:`SNAPSHOT_EVERY`-th) keeps a snapshot (a deep copy)
    when it is first told from, which also bounds both the replay and the chain of
    recipes the newest state keeps alive.

    ``replay(engine, step)`` (a module-level function, so that it pickles) advances an
    engine in place by one recorded step.
    """

    __slots__ = ("_depth", "_live", "_lock", "_parent", "_replay", "_snapshot", "_step")

    def __init__(self, engine: Any, replay: Any, parent: _Owned | None = None, step: Any = None,
                 depth: int = 0) -> None:
        self._live = engine
        self._replay = replay
        self._snapshot = None
        self._parent = parent
        self._step = step
        self._depth = depth
        self._lock = threading.Lock()

    def take(self) -> Any:
        """An engine at this state's position that the caller may change in place."""
        with self._lock:
            engine, self._live = self._live, None
            if engine is not None and (self._parent is None or self._depth >= SNAPSHOT_EVERY):
                self._snapshot = copy.deepcopy(engine)
                self._parent = self._step = None
                self._depth = 0
        return engine if engine is not None else self._rebuild()

    def child(self, engine: Any, step: Any) -> _Owned:
        """The owner of ``engine`` advanced from this state by ``step``."""
        return _Owned(engine, self._replay, self, step, self._depth + 1)

    def peek(self) -> Any:
        """The engine at this state's position, to read (not to change)."""
        engine = self._live
        if engine is None:
            engine = self._rebuild()
            with self._lock:
                if self._live is None:
                    self._live = engine
                engine = self._live
        return engine

    def _rebuild(self) -> Any:
        """A fresh copy of this state's engine: the nearest snapshot (or a live engine up
        the chain), copied, then the recorded steps replayed from there."""
        steps, node = [], self
        while True:
            with node._lock:
                base = node._live if node._live is not None else node._snapshot
                if base is not None:
                    engine = copy.deepcopy(base)
                    break
                steps.append(node._step)
                node = node._parent
        for step in reversed(steps):
            self._replay(engine, step)
        return engine

    def __reduce__(self) -> tuple:
        # pickle and copy.deepcopy: this state's engine, as the root of a new chain
        return (_Owned, (self.peek(), self._replay))


# --------------------------------------------------------------------------- scipy DE


class _Ask(Exception):
    """Raised by the feeding objective at the first batch it has no values for."""

    def __init__(self, X: np.ndarray) -> None:
        super().__init__("ask")
        self.X = X


_FEED = threading.local()


def _feed_objective(x: np.ndarray) -> np.ndarray:
    """The objective scipy's solver sees: serves told batches, raises at the next one.

    ``x`` has scipy's vectorised shape (n_var, S); it is checked against what was
    asked, so a replay that drifted from the original run fails loudly.
    """
    feed = _FEED.current
    X = np.array(x.T, dtype=np.float64)
    if feed.index < len(feed.batches):
        X_told, y = feed.batches[feed.index]
        if X_told.shape != X.shape or not np.array_equal(X_told, X):
            raise RuntimeError("ScipyDE: scipy asked for different points on replay; "
                               "the adapter does not support this scipy version")
        feed.index += 1
        return np.array(y, dtype=np.float64)
    raise _Ask(X)


def _vectorized_map(func: Any, x: np.ndarray) -> np.ndarray:
    """scipy's own map for ``vectorized=True`` (a module-level function, so picklable)."""
    return np.atleast_1d(func(x.T))


#: SciPy releases whose private DE solver class the ScipyDE adapter was checked against
#: (the floor in pyproject.toml to the version of the replay tests; outside them it warns).
SCIPY_CHECKED = ((1, 13), (1, 17))


def scipy_private() -> tuple[Any, Any]:
    """SciPy's ``DifferentialEvolutionSolver`` and ``MapWrapper``, two private names the
    adapter drives, or a RuntimeError that says what to do when a SciPy release moved them;
    a RuntimeWarning (once) for a SciPy outside :data:`SCIPY_CHECKED`."""
    import warnings

    import scipy

    version = tuple(int(x) for x in scipy.__version__.split(".")[:2] if x.isdigit())
    if not SCIPY_CHECKED[0] <= version <= SCIPY_CHECKED[1]:
        warnings.warn(f"the scipy-de baseline drives SciPy's private DifferentialEvolutionSolver, "
                      f"checked on SciPy {'.'.join(map(str, SCIPY_CHECKED[0]))} to "
                      f"{'.'.join(map(str, SCIPY_CHECKED[1]))}; this is SciPy {scipy.__version__} "
                      "(a change of its behaviour stops the run with an error rather than running "
                      "another algorithm)", RuntimeWarning, stacklevel=3)
    try:
        from scipy._lib._util import MapWrapper
        from scipy.optimize._differentialevolution import DifferentialEvolutionSolver
    except ImportError as exc:
        raise RuntimeError(f"the scipy-de baseline needs SciPy's DifferentialEvolutionSolver, "
                           f"which SciPy {scipy.__version__} no longer has where it looks ({exc}); "
                           "use emaphm's own 'de', or a SciPy from 1.13 to 1.17") from None
    return DifferentialEvolutionSolver, MapWrapper


def _rng_keyword(cls: Any, rng: np.random.Generator) -> dict[str, Any]:
    """scipy >= 1.15 takes ``rng=``; older versions ``seed=`` (a Generator works for both)."""
    params = inspect.signature(cls).parameters
    return {"rng": rng} if "rng" in params else {"seed": rng}


@dataclass
class _Feed:
    batches: list
    index: int = 0


def _generation(solver: Any, batches: list) -> np.ndarray | None:
    """Run one generation of ``solver``, in place, on the told ``batches``.

    Returns ``None`` when the generation completed (``solver`` is then at the start of
    the next one), or the points ``X`` of the first batch the generation still needs;
    ``solver`` is then left where it was (its attributes and its random stream are
    restored, see :func:`_checkpoint`).
    """
    restore = _checkpoint(solver)
    previous = getattr(_FEED, "current", None)
    _FEED.current = _Feed(batches)
    try:
        next(solver)
    except _Ask as ask:
        restore()
        return ask.X
    finally:
        _FEED.current = previous
    return None


def _checkpoint(solver: Any) -> Any:
    """A cheap undo of an interrupted generation: returns ``restore()``.

    Saves the solver's attributes (arrays copied, for the in-place updates of
    ``population``, ``population_energies`` and the rest) and its Generator's state;
    a deep copy of the whole solver did the same at about twenty times the cost. An
    interrupted generation (``_Ask`` raised inside it) only reassigns attributes,
    changes those arrays and draws from the stream.
    """
    saved = {name: value.copy() if isinstance(value, np.ndarray) else value
             for name, value in vars(solver).items()}
    rng = solver.random_number_generator
    rng_state = rng.bit_generator.state

    def restore() -> None:
        vars(solver).clear()
        vars(solver).update(saved)
        rng.bit_generator.state = rng_state

    return restore


def _de_step(solver: Any, batches: list | None) -> None:
    """Advance scipy's solver in place by one recorded step: the batches that completed
    its generation (``None``: a step within a generation, which leaves it alone)."""
    if batches is not None and _generation(solver, batches) is not None:
        raise RuntimeError("ScipyDE: scipy asked for different points on replay; "
                           "the adapter does not support this scipy version")


@dataclass(frozen=True, eq=False)
class ScipyDEState:
    """State of a :class:`ScipyDE` run (a value: ``tell`` returns a new one).

    ==========  =================  ===================================================
    Field       Shape / type       Meaning
    ==========  =================  ===================================================
    bounds      Bounds             search box
    rng         Generator          the stream the run was seeded from (scipy draws
                                   from its own fork of it, inside the solver)
    engine      private            owner of scipy's solver (see ``solver``)
    told        tuple              ``(X, y)`` batches told in the current generation
    pending     (pop_size, n_var)  the points scipy asks for next, problem coordinates, as
                                   scipy made them (``ask`` clips off round-off)
    best_x      (n_var,)           best point so far, problem coordinates
    best_f      float              its fitness
    nfev        int                evaluations so far
    nit         int                iterations (``tell`` calls) so far
    history     (nit,)             best fitness after each iteration
    ==========  =================  ===================================================

    ``solver``: scipy's solver at the start of the current generation; to read, not
    to change or keep (the newest state hands it on to the next ``tell``, which
    advances it in place; an older state's is rebuilt on demand, see :class:`_Owned`).
    """

    bounds: Bounds
    rng: np.random.Generator
    engine: _Owned
    told: tuple
    pending: np.ndarray
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray

    @property
    def solver(self) -> Any:
        """scipy's solver at the start of the current generation (read it; do not change
        or keep it)."""
        return self.engine.peek()


@dataclass(frozen=True)
class ScipyDE:
    """scipy's differential evolution (``best1bin`` by default), vectorised, deferred updating.

    =============  ==================  ==============  ==========================================
    Parameter      Type                Default         Meaning
    =============  ==================  ==============  ==========================================
    pop_size       int >= 5            48              population size (scipy's ``popsize`` is a
                                                       multiplier of ``n_var``; here the total,
                                                       as for the other algorithms: 48 = 6 x 8,
                                                       close to the paper's 50, where scipy's own
                                                       default, 15 x 8 = 120, would cost 2.4 times
                                                       as much per generation)
    strategy       str                 "best1bin"      scipy's ``strategy``
    mutation       float or pair       (0.5, 1.0)      scipy's ``mutation`` (a pair dithers)
    recombination  float in [0, 1]     0.7             scipy's ``recombination``
    max_iter       int >= 1            200             iteration budget of the default
                                                       termination (as emaphm's DE)
    patience       int >= 1            50              iterations of the default stall rule (as
                                                       emaphm's DE: a generational DE's best
                                                       moves in rare steps)
    =============  ==================  ==============  ==========================================

    The initial population is a Latin hypercube sample (scipy's default ``init``),
    drawn by :class:`scipy.stats.qmc.LatinHypercube` from the run's stream and passed
    to scipy as ``init``, so that ``pop_size`` is exact. The default termination is
    emaphm's: ``MaxIterations(max_iter) | StallTolerance(1e-9, patience)`` (scipy's own
    ``tol`` test is not used).
    """

    pop_size: int = 48
    strategy: str = "best1bin"
    mutation: float | tuple[float, float] = (0.5, 1.0)
    recombination: float = 0.7
    max_iter: int = 200
    patience: int = 50

    name: ClassVar[str] = "scipy-de"

    def __post_init__(self) -> None:
        object.__setattr__(self, "pop_size", check_int(
            "ScipyDE", "pop_size", self.pop_size, 5, " (scipy needs at least 5 members)"))
        if not isinstance(self.strategy, str):
            raise ValueError(f"ScipyDE: strategy must be a scipy strategy name such as "
                             f"'best1bin', got {self.strategy!r}")
        m = self.mutation
        if isinstance(m, (tuple, list, np.ndarray)):
            if len(m) != 2:
                raise ValueError(f"ScipyDE: mutation must be a number in [0, 2) or a pair, got {m!r}")
            lo = check_real("ScipyDE", "mutation[0]", m[0], 0.0, 2.0, hi_open=True)
            hi = check_real("ScipyDE", "mutation[1]", m[1], 0.0, 2.0, hi_open=True)
            if lo > hi:
                raise ValueError(f"ScipyDE: mutation pair must be (low, high) with low <= high, got {m!r}")
            object.__setattr__(self, "mutation", (lo, hi))
        else:
            object.__setattr__(self, "mutation",
                               check_real("ScipyDE", "mutation", m, 0.0, 2.0, hi_open=True))
        object.__setattr__(self, "recombination",
                           check_real("ScipyDE", "recombination", self.recombination, 0.0, 1.0))
        object.__setattr__(self, "max_iter", check_int("ScipyDE", "max_iter", self.max_iter, 1))
        object.__setattr__(self, "patience", check_int("ScipyDE", "patience", self.patience, 1))
        DifferentialEvolutionSolver, _ = scipy_private()
        known = {*getattr(DifferentialEvolutionSolver, "_binomial", ()),
                 *getattr(DifferentialEvolutionSolver, "_exponential", ())}
        if known and self.strategy not in known:
            raise ValueError(f"ScipyDE: unknown strategy {self.strategy!r}; choose one of "
                             f"{', '.join(sorted(known))}")

    def default_termination(self) -> Termination:
        """``MaxIterations(max_iter) | StallTolerance(1e-9, patience)``."""
        return MaxIterations(self.max_iter) | StallTolerance(1e-9, self.patience)

    def initial_population(self, bounds: Bounds, rng: np.random.Generator) -> np.ndarray:
        """The Latin hypercube initial population, problem coordinates, (pop_size, n_var)."""
        from scipy.stats import qmc

        U = qmc.LatinHypercube(d=bounds.n_var, **_rng_keyword(qmc.LatinHypercube, rng)).random(self.pop_size)
        return bounds.from_normalized(U)

    def solver(self, bounds: Bounds, init: np.ndarray, rng: np.random.Generator) -> Any:
        """The scipy solver this configuration drives (no objective calls yet)."""
        DifferentialEvolutionSolver, MapWrapper = scipy_private()
        solver = DifferentialEvolutionSolver(
            _feed_objective, list(zip(bounds.lo.tolist(), bounds.hi.tolist())),
            strategy=self.strategy, maxiter=1_000_000, mutation=self.mutation,
            recombination=self.recombination, polish=False, init=init,
            **_rng_keyword(DifferentialEvolutionSolver, rng),
            tol=0.0, atol=0.0, updating="deferred", vectorized=True)
        solver._mapwrapper = MapWrapper(_vectorized_map)  # picklable (scipy's is a closure)
        return solver

    def init(self, bounds: Any, rng: np.random.Generator) -> ScipyDEState:
        """Draw the initial population; it is what the first ``ask`` returns."""
        bounds = as_bounds(bounds)
        rng = child_rng(rng)
        init = self.initial_population(bounds, rng)
        # scipy draws from a fork (same stream): its solver changes in place, the state's
        # rng must not
        solver = self.solver(bounds, init, fork_rng(rng))
        pending = _generation(solver, [])
        return ScipyDEState(
            bounds=bounds, rng=rng, engine=_Owned(solver, _de_step), told=(),
            pending=frozen(pending), **start(bounds))

    def ask(self, state: ScipyDEState) -> np.ndarray:
        """The points scipy asks for next (problem coordinates; clipping only removes the
        round-off of scipy's scaling, at most one ulp)."""
        return np.clip(state.pending, state.bounds.lo, state.bounds.hi)

    def tell(self, state: ScipyDEState, X: np.ndarray, y: np.ndarray) -> ScipyDEState:
        """Feed one batch to scipy; advance the snapshot when its generation completes."""
        X, _, y = check_told(state, X, y, len(state.pending))
        if not np.array_equal(X, self.ask(state)):
            raise ValueError("ScipyDE.tell: X must be the array returned by ask(state)")
        batches = [*state.told, (state.pending, y)]
        solver = state.engine.take()  # in place when state is the newest, else a rebuilt copy
        pending = _generation(solver, batches)
        if pending is None:           # the generation is complete: ask the next one
            step, told = batches, ()
            pending = _generation(solver, [])
        else:                         # scipy needs another batch in this generation
            step, told = None, tuple(batches)
        return dataclasses.replace(state, engine=state.engine.child(solver, step), told=told,
                                   pending=frozen(pending), **advance(state, X, y))


# --------------------------------------------------------------------------- CMA-ES


class _Randn:
    """cma's ``randn`` option over a private Generator (cma otherwise uses ``np.random``)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def __call__(self, *shape: int) -> np.ndarray:
        return self.rng.standard_normal(shape)


def _cma_step(es: Any, step: tuple) -> None:
    """Advance cma's strategy in place by one recorded ``tell`` (and its ``ask``)."""
    solutions, fitness = step
    es.tell([s.copy() for s in solutions], list(fitness))
    es.ask()


@dataclass(frozen=True, eq=False)
class CMAESState:
    """State of a :class:`CMAES` run (a value: ``tell`` returns a new one).

    ==========  =================  ===================================================
    Field       Shape / type       Meaning
    ==========  =================  ===================================================
    bounds      Bounds             search box
    rng         Generator          the stream the run was seeded from (cma draws from
                                   its own fork of it, inside the strategy)
    engine      private            owner of cma's strategy (see ``es``)
    pending     list of arrays     cma's solutions (normalised box) awaiting their fitness
    best_x      (n_var,)           best point so far, problem coordinates
    best_f      float              its fitness
    nfev, nit, history             as for every optimizer
    ==========  =================  ===================================================

    ``es``: the ``cma.CMAEvolutionStrategy`` at this state, already asked for
    ``pending``; to read, not to change or keep (the newest state hands it on to the
    next ``tell``, which advances it in place; an older state's is rebuilt on demand,
    see :class:`_Owned`).
    """

    bounds: Bounds
    rng: np.random.Generator
    engine: _Owned
    pending: tuple
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray

    @property
    def es(self) -> Any:
        """cma's strategy at this state (read it; do not change or keep it)."""
        return self.engine.peek()


@dataclass(frozen=True)
class CMAES:
    """CMA-ES (Hansen), ``cma.CMAEvolutionStrategy``, searching the normalised box ``[0, 1]^n_var``.

    ===========  ==============  =======  ===================================================
    Parameter    Type            Default  Meaning
    ===========  ==============  =======  ===================================================
    pop_size     int >= 2        10       lambda, samples per iteration: cma's default for
                 or None                  the 8-D fault vector, 4 + floor(3 ln 8); None: cma's
                                          default for the box at hand, 4 + floor(3 ln n_var)
    sigma0       float in (0,1]  0.3      initial step size, fraction of each range (cma's
                                          advice: about a quarter to a third of the range)
    x0           "center" or     "center" initial mean: the box centre or a uniform
                 "random"                 random point drawn from the run's stream
    max_iter     int >= 1        400      iteration budget of the default termination
    patience     int >= 1        40       iterations of the default stall rule (CMA-ES
                                          improves in smaller steps than the swarms)
    ===========  ==============  =======  ===================================================

    The default termination is ``MaxIterations(max_iter) | StallTolerance(1e-9,
    patience)``; cma's own stopping tests are not used. Randomness: cma's sampler
    is given a private Generator (option ``randn``), so the global ``np.random`` state
    is neither read nor changed. Non-finite fitness values reach cma as a huge finite
    number (cma ranks its samples, so only the order matters).
    """

    pop_size: int | None = 10
    sigma0: float = 0.3
    x0: str = "center"
    max_iter: int = 400
    patience: int = 40

    name: ClassVar[str] = "cmaes"

    def __post_init__(self) -> None:
        if self.pop_size is not None:
            object.__setattr__(self, "pop_size", check_int("CMAES", "pop_size", self.pop_size, 2))
        object.__setattr__(self, "sigma0", check_real("CMAES", "sigma0", self.sigma0, 0.0, 1.0, lo_open=True))
        if self.x0 not in ("center", "random"):
            raise ValueError(f"CMAES: x0 must be 'center' or 'random', got {self.x0!r}")
        object.__setattr__(self, "max_iter", check_int("CMAES", "max_iter", self.max_iter, 1))
        object.__setattr__(self, "patience", check_int("CMAES", "patience", self.patience, 1))

    def default_termination(self) -> Termination:
        """``MaxIterations(max_iter) | StallTolerance(1e-9, patience)``."""
        return MaxIterations(self.max_iter) | StallTolerance(1e-9, self.patience)

    def init(self, bounds: Any, rng: np.random.Generator) -> CMAESState:
        """Start the strategy and ask it for the first generation."""
        import cma

        bounds = as_bounds(bounds)
        if bounds.n_var == 1:
            raise ValueError("CMAES: cma needs at least 2 variables, got 1")
        rng = child_rng(rng)
        x0 = np.full(bounds.n_var, 0.5) if self.x0 == "center" else rng.random(bounds.n_var)
        # cma draws from a fork (same stream): its strategy changes in place, the state's
        # rng must not
        opts = {"bounds": [0.0, 1.0], "randn": _Randn(fork_rng(rng)), "verbose": -9, "verb_log": 0,
                "verb_disp": 0}
        if self.pop_size is not None:
            opts["popsize"] = self.pop_size
        es = cma.CMAEvolutionStrategy(x0, self.sigma0, opts)
        pending = tuple(np.array(s, dtype=np.float64) for s in es.ask())
        return CMAESState(bounds=bounds, rng=rng, engine=_Owned(es, _cma_step), pending=pending,
                          **start(bounds))

    def ask(self, state: CMAESState) -> np.ndarray:
        """cma's pending solutions in problem coordinates, shape (lambda, n_var)."""
        return state.bounds.from_normalized(np.clip(np.array(state.pending), 0.0, 1.0))

    def tell(self, state: CMAESState, X: np.ndarray, y: np.ndarray) -> CMAESState:
        """Tell cma the fitness of the pending solutions and ask for the next ones."""
        X, _, y = check_told(state, X, y, len(state.pending))
        big = np.finfo(np.float64).max / 1e3
        step = (state.pending, np.where(np.isfinite(y), y, big).tolist())
        es = state.engine.take()          # in place when state is the newest, else a rebuilt copy
        es.tell([s.copy() for s in step[0]], step[1])
        pending = tuple(np.array(s, dtype=np.float64) for s in es.ask())
        return dataclasses.replace(state, engine=state.engine.child(es, step), pending=pending,
                                   **advance(state, X, y))


# --------------------------------------------------------------------------- registry

#: The baselines by registry name.
BASELINES: dict[str, type] = {"scipy-de": ScipyDE, "cmaes": CMAES}
