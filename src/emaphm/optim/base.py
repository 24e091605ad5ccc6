"""Shared machinery of the optimizers: bounds, termination, results and the run loop.

The optimizers in :mod:`emaphm.optim` know nothing about actuators. They see a box
``(lo, hi)`` and a *batch* objective

.. code-block:: text

    f(X) -> y        X: (n_pop, n_var) float64, problem coordinates, every row inside the box
                     y: (n_pop,)       float64; NaN, +inf and -inf all read as +inf (worst)

Every optimizer is a frozen configuration object with three pure methods
(evosax / pymoo style)::

    state = opt.init(bounds, rng)       # draws the initial population
    X = opt.ask(state)                  # points to evaluate, problem coordinates
    state = opt.tell(state, X, f(X))    # a NEW state; the input state is never modified

The first ``ask`` returns the initial population, so the initial evaluation is an
ordinary ask/tell pair and counts as iteration 1 (``nit`` counts ``tell`` calls).
``tell`` takes the points it is given as the truth (mapped back to the normalised box), so a
caller that evaluates a modified copy of the asked points (rounded, repaired) stays
consistent as long as it passes what it evaluated. All randomness is drawn in ``init``
and ``tell`` from the state's own Generator, forked first, so ``ask`` is pure and
``tell`` is a function of its arguments.
:func:`minimize` is nothing but that loop plus a :class:`Termination` check and an
optional callback; :func:`resume` continues the same loop from any state, for example
one unpickled from a checkpoint, and reproduces the uninterrupted run exactly.

Coordinates
-----------
Populations are held normalised to the normalised box ``[0, 1]^n_var`` (as in
:func:`scipy.optimize.differential_evolution`) and scaled at the boundary by
:class:`Bounds`. Points that an update moves outside the box are **clipped** (projected
onto the nearest face), never reflected or re-sampled. Projection is chosen on purpose:
in the fault-identification problem the healthy value of most fault components is the
bound ``k_i = 0`` itself, and clipping lets a search land exactly on it.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..seeds import as_generator

__all__ = [
    "AnyOf",
    "Bounds",
    "MaxEvaluations",
    "MaxIterations",
    "OptimizeResult",
    "Optimizer",
    "StallTolerance",
    "State",
    "Termination",
    "WallClock",
    "as_bounds",
    "minimize",
    "remaining",
    "resume",
]

Objective = Callable[[np.ndarray], Any]


# --------------------------------------------------------------------------- bounds


@dataclass(frozen=True, eq=False)
class Bounds:
    """A validated axis-aligned box ``lo <= x <= hi`` and the map to the normalised box.

    Build it with :func:`as_bounds`, which accepts a ``(lo, hi)`` pair.

    ========  =================  ======================================================
    Field     Shape              Meaning
    ========  =================  ======================================================
    lo        (n_var,) float64   lower bounds, problem coordinates (read-only array)
    hi        (n_var,) float64   upper bounds, problem coordinates, ``hi > lo`` (read-only)
    ========  =================  ======================================================
    """

    lo: np.ndarray
    hi: np.ndarray

    @property
    def n_var(self) -> int:
        """Number of decision variables."""
        return self.lo.shape[0]

    @property
    def width(self) -> np.ndarray:
        """``hi - lo``, shape (n_var,)."""
        return self.hi - self.lo

    def from_normalized(self, U: np.ndarray) -> np.ndarray:
        """Map normalised points ``U`` (..., n_var) to problem coordinates, clipped into the box.

        The final clip only removes floating-point round-off (``lo + 1.0 * (hi - lo)``
        can exceed ``hi`` by one ulp), so every returned point satisfies ``lo <= x <= hi``.
        """
        X = self.lo + np.asarray(U, dtype=np.float64) * (self.hi - self.lo)
        return np.clip(X, self.lo, self.hi, out=X)

    def to_normalized(self, X: np.ndarray) -> np.ndarray:
        """Map points in problem coordinates ``X`` (..., n_var) to the normalised box, clipped to [0, 1]."""
        U = (np.asarray(X, dtype=np.float64) - self.lo) / (self.hi - self.lo)
        return np.clip(U, 0.0, 1.0, out=U)

    def from_unit(self, U: np.ndarray) -> np.ndarray:
        """The 0.3 name of :meth:`from_normalized` ("unit" means a production unit in
        emaphm), kept for one release with a warning."""
        _renamed("Bounds.from_unit", "Bounds.from_normalized")
        return self.from_normalized(U)

    def to_unit(self, X: np.ndarray) -> np.ndarray:
        """The 0.3 name of :meth:`to_normalized`, kept for one release with a warning."""
        _renamed("Bounds.to_unit", "Bounds.to_normalized")
        return self.to_normalized(X)

    def __repr__(self) -> str:
        return f"Bounds(lo={self.lo.tolist()}, hi={self.hi.tolist()})"


def _renamed(old: str, new: str) -> None:
    import warnings

    warnings.warn(f"{old} is renamed {new}; the old name goes in the next release",
                  DeprecationWarning, stacklevel=3)


def as_bounds(bounds: Any) -> Bounds:
    """Validate ``bounds`` and return a :class:`Bounds`.

    Parameters
    ----------
    bounds : Bounds or pair of array-like
        ``(lo, hi)``: two 1-D array-likes of the same length ``n_var >= 1``, finite, with
        ``hi > lo`` in every component. A :class:`Bounds` is returned unchanged. The
        scipy-style list of ``(min, max)`` pairs is *not* accepted (for ``n_var = 2`` it
        would be ambiguous).

    Raises
    ------
    ValueError
        With a message naming the offending part.
    """
    if isinstance(bounds, Bounds):
        return bounds
    try:
        n_parts = len(bounds)
    except TypeError:
        n_parts = -1
    if n_parts != 2:
        raise ValueError(
            "bounds must be a pair (lo, hi) of array-likes of shape (n_var,), "
            f"got {type(bounds).__name__}"
            + (f" of length {n_parts}" if n_parts >= 0 else "")
        )
    try:
        lo = np.array(bounds[0], dtype=np.float64)
        hi = np.array(bounds[1], dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"bounds: lo and hi must be numeric array-likes ({exc})") from None
    if lo.ndim != 1 or hi.ndim != 1:
        raise ValueError(
            f"bounds: lo and hi must be 1-D of shape (n_var,), got shapes {lo.shape} and {hi.shape}"
        )
    if lo.shape != hi.shape:
        raise ValueError(
            f"bounds: lo and hi must have the same shape, got {lo.shape} and {hi.shape}"
        )
    if lo.size == 0:
        raise ValueError("bounds: need at least one variable, got empty lo and hi")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ValueError("bounds: lo and hi must be finite (no NaN or inf)")
    bad = np.flatnonzero(~(hi > lo))
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"bounds: hi must be greater than lo in every component; index {i} has "
            f"lo={float(lo[i])!r}, hi={float(hi[i])!r}"
        )
    lo.flags.writeable = False
    hi.flags.writeable = False
    return Bounds(lo, hi)


# --------------------------------------------------------------------------- state helpers


@runtime_checkable
class State(Protocol):
    """What every optimizer state exposes (the rest is algorithm-specific).

    ===========  =================  ====================================================
    Attribute    Type               Meaning
    ===========  =================  ====================================================
    bounds       Bounds             the search box
    rng          numpy Generator    the run's private random stream
    best_x       (n_var,) float64   best point evaluated so far, problem coordinates
    best_f       float              its fitness (``inf`` until a finite value is seen)
    nfev         int                objective evaluations so far (points, not calls)
    nit          int                completed iterations (``tell`` calls)
    history      (nit,) float64     ``best_f`` after each iteration
    ===========  =================  ====================================================
    """

    bounds: Bounds
    rng: np.random.Generator
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray


def fork_rng(rng: np.random.Generator) -> np.random.Generator:
    """Return an independent copy of ``rng`` at the same position of its stream.

    ``tell`` draws from a fork so that the input state is never modified (calling
    ``tell`` twice on the same state gives the same new state).
    """
    bg = rng.bit_generator
    new = type(bg)(0)
    new.state = bg.state
    return np.random.Generator(new)


def child_rng(rng: np.random.Generator) -> np.random.Generator:
    """Derive a run's private stream from the caller's generator.

    Advances ``rng`` by four 64-bit draws and seeds a fresh generator of the same kind
    from them through :class:`numpy.random.SeedSequence`. So passing the same Generator
    to two runs gives two different, independent runs (numpy's convention), while the
    whole run remains a function of the generator's state.
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(
            f"rng must be a numpy.random.Generator, got {type(rng).__name__}; "
            "use numpy.random.default_rng(seed)"
        )
    entropy = rng.integers(0, 2**63, size=4, dtype=np.int64).tolist()
    return np.random.Generator(type(rng.bit_generator)(np.random.SeedSequence(entropy)))


def check_told(
    state: State, X: Any, y: Any, n_pop: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate what is passed to ``tell``; return ``(X, U, y)``.

    ``X`` is a float64 array, ``U`` is ``X`` mapped to the normalised box; ``y`` is float64
    with every non-finite value (NaN, +inf, -inf) replaced by ``+inf``.
    """
    X = np.asarray(X, dtype=np.float64)
    n_var = state.bounds.n_var
    if X.shape != (n_pop, n_var):
        raise ValueError(
            f"tell: X must have shape ({n_pop}, {n_var}) as returned by ask, got {X.shape}"
        )
    if not np.isfinite(X).all():
        raise ValueError("tell: X contains NaN or inf; pass the array returned by ask")
    y = sanitize_fitness(y, n_pop)
    return X, state.bounds.to_normalized(X), y


def sanitize_fitness(y: Any, n_pop: int) -> np.ndarray:
    """Return ``y`` as a fresh float64 array of shape (n_pop,), non-finite -> ``+inf``."""
    try:
        y = np.array(y, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"fitness values must be real numbers ({exc})") from None
    if y.shape != (n_pop,):
        raise ValueError(
            f"fitness must have shape ({n_pop},), one value per asked point, got shape {y.shape}"
        )
    y[~np.isfinite(y)] = np.inf
    return y


def update_best(
    best_x: np.ndarray, best_f: float, X: np.ndarray, y: np.ndarray, first: bool
) -> tuple[np.ndarray, float]:
    """Return the new ``(best_x, best_f)`` after evaluating ``X`` with fitness ``y``.

    On the first iteration the best point is taken from ``X`` even when every value is
    ``inf``, so ``best_x`` is always a point inside the box.
    """
    i = int(np.argmin(y))
    if first or y[i] < best_f:
        return np.array(X[i], dtype=np.float64), float(y[i])
    return best_x, best_f


def start(bounds: Bounds) -> dict[str, Any]:
    """The bookkeeping fields shared by every state before the first ``tell``.

    Returns ``best_x`` (the box centre, a placeholder until something is evaluated),
    ``best_f = inf``, ``nfev = nit = 0`` and an empty ``history``; the counterpart of
    :func:`advance`.
    """
    return {
        "best_x": frozen(bounds.from_normalized(np.full(bounds.n_var, 0.5))),
        "best_f": np.inf,
        "nfev": 0,
        "nit": 0,
        "history": frozen(np.empty(0)),
    }


def advance(state: State, X: np.ndarray, y: np.ndarray) -> dict[str, Any]:
    """The bookkeeping fields shared by every state after one ``tell``.

    Returns a dict with ``best_x``, ``best_f``, ``nfev``, ``nit`` and ``history``, ready
    for :func:`dataclasses.replace`.
    """
    best_x, best_f = update_best(state.best_x, state.best_f, X, y, first=state.nit == 0)
    return {
        "best_x": frozen(best_x),
        "best_f": best_f,
        "nfev": state.nfev + y.shape[0],
        "nit": state.nit + 1,
        "history": frozen(np.append(state.history, best_f)),
    }


def frozen(a: np.ndarray) -> np.ndarray:
    """Mark an array read-only (states are values) and return it."""
    a.flags.writeable = False
    return a


def check_int(owner: str, name: str, value: Any, minimum: int, why: str = "") -> int:
    """Validate an integer option ``>= minimum`` and return it as ``int``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise ValueError(
            f"{owner}: {name} must be an integer >= {minimum}{why}, got {value!r}"
        )
    return int(value)


def check_real(
    owner: str,
    name: str,
    value: Any,
    lo: float,
    hi: float,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """Validate a real option inside an interval and return it as ``float``."""
    interval = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if ok:
        v = float(value)
        ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        raise ValueError(f"{owner}: {name} must be a number in {interval}, got {value!r}")
    return float(value)


# --------------------------------------------------------------------------- termination


@runtime_checkable
class Termination(Protocol):
    """A stopping rule: ``check(state, elapsed_s)`` returns a reason string or ``None``.

    Terminations only read ``state.nit``, ``state.nfev`` and ``state.history`` (and the
    wall-clock time of the current :func:`minimize` / :func:`resume` call), so any
    optimizer state works with any termination. Combine them with ``|``.
    """

    def check(self, state: State, elapsed_s: float) -> str | None: ...


#: What a termination leaves of its budget when it has none of that kind: no limit.
UNLIMITED = (math.inf, math.inf)


def remaining(termination: Any, nfev: int, elapsed_s: float) -> tuple[float, float]:
    """``(evaluations, seconds)`` that ``termination`` leaves after ``nfev`` evaluations and
    ``elapsed_s`` seconds: what a solver that works in larger steps than one iteration (a
    least-squares pass, a polish) may spend inside one of them. ``inf`` where it sets no
    such limit, and for ``None`` or a termination without a ``remaining`` method (an
    iteration count or a stall rule cannot say in advance)."""
    if termination is None or not hasattr(termination, "remaining"):
        return UNLIMITED
    return termination.remaining(nfev, elapsed_s)


class _Combinable:
    """Adds ``a | b`` -> :class:`AnyOf` to the termination dataclasses."""

    def __or__(self, other: Any) -> AnyOf:
        if not isinstance(other, Termination):
            return NotImplemented
        return AnyOf(self, other)  # type: ignore[arg-type]

    def __ror__(self, other: Any) -> AnyOf:
        if not isinstance(other, Termination):
            return NotImplemented
        return AnyOf(other, self)  # type: ignore[arg-type]


@dataclass(frozen=True)
class MaxIterations(_Combinable):
    """Stop after exactly ``n`` iterations (``nit == n``). Reason: ``"max_iterations"``.

    The initial evaluation of the population is iteration 1, so a run stopped by
    ``MaxIterations(n)`` has evaluated ``n * pop_size`` points.

    ====  =====  ===========================================
    Name  Type   Meaning
    ====  =====  ===========================================
    n     int    iteration budget, ``>= 1``
    ====  =====  ===========================================
    """

    n: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "n", check_int("MaxIterations", "n", self.n, 1))

    def check(self, state: State, elapsed_s: float) -> str | None:
        return "max_iterations" if state.nit >= self.n else None

    def remaining(self, nfev: int, elapsed_s: float) -> tuple[float, float]:
        return UNLIMITED


@dataclass(frozen=True)
class MaxEvaluations(_Combinable):
    """Stop once ``nfev >= n``. Reason: ``"max_evaluations"``.

    Checked after each whole population, so a run may overshoot the budget by less
    than one population (``nfev < n + pop_size``); it never stops short of it.

    ====  =====  ===============================================
    Name  Type   Meaning
    ====  =====  ===============================================
    n     int    budget of objective evaluations (points), >= 1
    ====  =====  ===============================================
    """

    n: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "n", check_int("MaxEvaluations", "n", self.n, 1))

    def check(self, state: State, elapsed_s: float) -> str | None:
        return "max_evaluations" if state.nfev >= self.n else None

    def remaining(self, nfev: int, elapsed_s: float) -> tuple[float, float]:
        return self.n - nfev, math.inf


@dataclass(frozen=True)
class StallTolerance(_Combinable):
    """Stop when the best fitness has improved by less than ``tol`` over ``patience``
    iterations. Reason: ``"stall"``.

    Formally, with ``h = state.history`` (best fitness after each iteration), stop when
    ``len(h) > patience`` and ``h[-1 - patience] - h[-1] < tol``. The tolerance is
    *absolute*, in the fitness's own unit, as the paper's "error between two successive runs is
    less than 1e-9" (Baldo et al. 2023, sec. 3.1.2). While the best fitness is still
    ``inf`` (no finite value seen yet) the rule never fires.

    Why ``patience=20`` and not 1: the paper's "two successive runs" read literally is
    ``patience=1``. But the best-so-far value of a population is flat for several
    iterations at a time while its members are still moving (PSO's global best, GWO's
    alpha and DE's best member only change when some member beats them), so with
    ``patience=1`` PSO routinely stops within its first few iterations, far from the
    optimum (on 8-D sphere, Rastrigin and Rosenbrock it stopped PSO after 4-8
    iterations at f = 3.4, 51 and 620). Twenty iterations, a tenth of the paper's
    200-iteration PSO budget, rides out PSO's plateaus (on Rastrigin and Rosenbrock the
    run went the full 200 iterations; on the sphere it stopped near iteration 170 at
    f ~ 6e-11, i.e. once converged, as intended).
    Each optimizer's ``default_termination`` picks the patience its own plateaus need:
    PSO 20, DE 50 and GWO ``max_iter // 3`` (their class docstrings say why).

    ========  ======  =============================================================
    Name      Type    Meaning
    ========  ======  =============================================================
    tol       float   minimal improvement that counts, the fitness's own unit, ``>= 0``
                      (default 1e-9, the paper's tolerance; 0 never stops)
    patience  int     iterations over which the improvement is measured, ``>= 1``
                      (default 20, PSO's)
    ========  ======  =============================================================
    """

    tol: float = 1e-9
    patience: int = 20

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "tol", check_real("StallTolerance", "tol", self.tol, 0.0, math.inf, hi_open=True)
        )
        object.__setattr__(
            self, "patience", check_int("StallTolerance", "patience", self.patience, 1)
        )

    def check(self, state: State, elapsed_s: float) -> str | None:
        h = state.history
        if len(h) <= self.patience:
            return None
        old, new = float(h[-1 - self.patience]), float(h[-1])
        if not math.isfinite(new):
            return None
        return "stall" if old - new < self.tol else None

    def remaining(self, nfev: int, elapsed_s: float) -> tuple[float, float]:
        return UNLIMITED


@dataclass(frozen=True)
class WallClock(_Combinable):
    """Stop once the current call has run for ``seconds``. Reason: ``"wall_clock"``.

    Checked between iterations, so one iteration started before the limit finishes.
    The clock restarts on :func:`resume`.

    =======  ======  =======================================
    Name     Type    Meaning
    =======  ======  =======================================
    seconds  float   wall-time budget in s, ``> 0``
    =======  ======  =======================================
    """

    seconds: float

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "seconds",
            check_real("WallClock", "seconds", self.seconds, 0.0, math.inf, lo_open=True, hi_open=True),
        )

    def check(self, state: State, elapsed_s: float) -> str | None:
        return "wall_clock" if elapsed_s >= self.seconds else None

    def remaining(self, nfev: int, elapsed_s: float) -> tuple[float, float]:
        return math.inf, self.seconds - elapsed_s


@dataclass(frozen=True, init=False)
class AnyOf(_Combinable):
    """Stop as soon as any of ``terms`` says so; the first one (in order) gives the reason.

    ``AnyOf(a, b)`` is the same as ``a | b``; nested combinations are flattened.
    """

    terms: tuple[Termination, ...]

    def __init__(self, *terms: Termination) -> None:
        if not terms:
            raise ValueError("AnyOf: needs at least one termination, got none")
        flat: list[Termination] = []
        for t in terms:
            if isinstance(t, AnyOf):
                flat.extend(t.terms)
            elif isinstance(t, Termination):
                flat.append(t)
            else:
                raise ValueError(
                    "AnyOf: every term must be a termination object with a "
                    f"check(state, elapsed_s) method, got {type(t).__name__}"
                )
        object.__setattr__(self, "terms", tuple(flat))

    def check(self, state: State, elapsed_s: float) -> str | None:
        for t in self.terms:
            reason = t.check(state, elapsed_s)
            if reason is not None:
                return reason
        return None

    def remaining(self, nfev: int, elapsed_s: float) -> tuple[float, float]:
        left = [remaining(t, nfev, elapsed_s) for t in self.terms]
        return min(e for e, _ in left), min(s for _, s in left)

    def __repr__(self) -> str:
        return " | ".join(repr(t) for t in self.terms)


# --------------------------------------------------------------------------- protocol + result


@runtime_checkable
class Optimizer(Protocol):
    """Interface of an optimizer configuration (frozen; all run data lives in the state).

    ===========================================  =========================================
    Member                                       Meaning
    ===========================================  =========================================
    ``name: str``                                short registry name ("de", "pso", "gwo")
    ``init(bounds, rng) -> State``               draw the initial population
    ``ask(state) -> X``                          (n_pop, n_var) points, problem coordinates
    ``tell(state, X, y) -> State``               new state; input state left untouched
    ``default_termination() -> Termination``     the documented default stopping rule
    ===========================================  =========================================
    """

    name: str

    def init(self, bounds: Any, rng: np.random.Generator) -> Any: ...

    def ask(self, state: Any) -> np.ndarray: ...

    def tell(self, state: Any, X: np.ndarray, y: np.ndarray) -> Any: ...

    def default_termination(self) -> Termination: ...


@dataclass(frozen=True, eq=False)
class OptimizeResult:
    """Outcome of :func:`minimize` / :func:`resume` (plain data, picklable).

    ==========  =================  ======================================================
    Field       Type               Meaning
    ==========  =================  ======================================================
    x           (n_var,) float64   best point found, problem coordinates (inside the box)
    fun         float              its fitness; ``inf`` if every evaluation failed
    nfev        int                objective evaluations (points)
    nit         int                iterations (the initial evaluation is iteration 1)
    history     (nit,) float64     best fitness after each iteration (non-increasing)
    reason      str                why it stopped: "max_iterations", "max_evaluations",
                                   "stall", "wall_clock" or "callback"
    elapsed_s   float              wall time of the call, s
    algorithm   str                optimizer name ("de", "pso", "gwo")
    ==========  =================  ======================================================
    """

    x: np.ndarray
    fun: float
    nfev: int
    nit: int
    history: np.ndarray
    reason: str
    elapsed_s: float
    algorithm: str


# --------------------------------------------------------------------------- run loop


def _as_generator(seed: Any) -> np.random.Generator:
    return as_generator(seed)


def _check_optimizer(optimizer: Any) -> None:
    if not isinstance(optimizer, Optimizer):
        raise ValueError(
            "optimizer must provide name, init, ask, tell and default_termination "
            f"(e.g. emaphm.optim.DE()), got {type(optimizer).__name__}"
        )


def minimize(
    objective: Objective,
    bounds: Any,
    optimizer: Optimizer,
    *,
    seed: int | np.random.Generator,
    termination: Termination | None = None,
    callback: Callable[[Any], bool | None] | None = None,
) -> OptimizeResult:
    """Minimise a batch objective over a box with an ask/tell optimizer.

    Parameters
    ----------
    objective : callable
        ``objective(X) -> y`` with ``X`` of shape (n_pop, n_var) in problem coordinates and
        ``y`` of shape (n_pop,). NaN and +/-inf values count as ``+inf``. ``X`` is a
        private copy, the objective may modify it.
    bounds : pair of array-like or Bounds
        ``(lo, hi)``, each of shape (n_var,), ``hi > lo``; see :func:`as_bounds`.
    optimizer : Optimizer
        A configuration such as ``DE()``, ``PSO()``, ``GWO()``.
    seed : int or numpy.random.Generator, keyword-only, required
        Source of all randomness. An int gives the same run every time; a Generator is
        advanced (so reusing it gives a new, independent run).
    termination : Termination, optional
        Stopping rule; ``None`` uses ``optimizer.default_termination()``.
    callback : callable, optional
        ``callback(state) -> bool | None`` called after every iteration with the new
        state (e.g. to log or to pickle a checkpoint). A truthy return stops the run
        with reason ``"callback"``.

    Returns
    -------
    OptimizeResult
    """
    _check_optimizer(optimizer)
    state = optimizer.init(as_bounds(bounds), _as_generator(seed))
    return resume(objective, optimizer, state, termination=termination, callback=callback)


def resume(
    objective: Objective,
    optimizer: Optimizer,
    state: Any,
    *,
    termination: Termination | None = None,
    callback: Callable[[Any], bool | None] | None = None,
) -> OptimizeResult:
    """Continue a run from ``state`` (fresh from ``init`` or unpickled from a checkpoint).

    Same loop and parameters as :func:`minimize` (which is ``init`` + ``resume``).
    Resuming from a state saved by a callback reproduces the uninterrupted run exactly:
    same ``x``, ``fun``, ``nfev``, ``nit`` and ``history``. ``termination`` is checked
    before the first iteration too, so resuming a finished run returns at once.
    """
    _check_optimizer(optimizer)
    if termination is None:
        termination = optimizer.default_termination()
    elif not isinstance(termination, Termination):
        raise ValueError(
            "termination must be a termination object such as MaxIterations(200), "
            f"got {type(termination).__name__}"
        )
    if callback is not None and not callable(callback):
        raise ValueError(f"callback must be callable, got {type(callback).__name__}")
    t0 = time.perf_counter()
    reason = termination.check(state, 0.0)
    while reason is None:
        X = optimizer.ask(state)
        y = sanitize_fitness(objective(X.copy()), X.shape[0])
        state = optimizer.tell(state, X, y)
        if callback is not None and callback(state):
            reason = "callback"
            break
        reason = termination.check(state, time.perf_counter() - t0)
    return OptimizeResult(
        x=np.array(state.best_x, dtype=np.float64),
        fun=float(state.best_f),
        nfev=int(state.nfev),
        nit=int(state.nit),
        history=np.array(state.history, dtype=np.float64),
        reason=reason,
        elapsed_s=time.perf_counter() - t0,
        algorithm=optimizer.name,
    )
