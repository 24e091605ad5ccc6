"""Differential evolution, DE/rand/1/bin (Storn & Price 1997; Baldo et al. 2023, Fig. 3).

One generation, for every target vector ``x_i`` of the population::

    pick r1, r2, r3 distinct and different from i          (uniformly at random)
    v   = x_r1 + F (x_r2 - x_r3)                             mutation (rand/1)
    u_j = v_j  if rand_j < CR or j == j_rand  else  x_ij     binomial crossover
    x_i <- u   if f(u) < f(x_i)                              greedy selection

The update is generational ("deferred", as ``updating='deferred'`` in scipy): every
trial of a generation is built from the same parent population, so the whole trial
population is one batch for the objective. All work happens in the normalised box;
components of the mutant that leave it are clipped to the nearest face.

The update equations are pure module-level functions (random numbers are passed in);
:class:`DE` only wires them into ``init``/``ask``/``tell``.
"""

from __future__ import annotations

import dataclasses
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

__all__ = [
    "DE",
    "DEState",
    "binomial_crossover",
    "distinct_indices",
    "greedy_selection",
    "rand1_mutation",
]


# --------------------------------------------------------------------------- pure updates


def distinct_indices(rng: np.random.Generator, n_pop: int, k: int = 3) -> np.ndarray:
    """For every row ``i`` draw ``k`` distinct indices in ``[0, n_pop)``, all ``!= i``.

    Uniform over ordered ``k``-tuples, vectorised and O(n_pop k^2): the ``j``-th draw is
    a uniform integer in ``[0, n_pop - 1 - j)`` mapped onto the ``j``-th integer not yet
    excluded (``i`` and the earlier draws), by stepping over the exclusions in ascending
    order; the new draw is then bubbled into that sorted list.

    ========  =====  ======================================
    Name      Shape  Meaning
    ========  =====  ======================================
    rng              random stream (advanced)
    n_pop            population size, ``>= k + 1``
    k                how many indices per row (3 for rand/1)
    returns   (n_pop, k) int64 index array
    ========  =====  ======================================
    """
    if n_pop < k + 1:
        raise ValueError(f"distinct_indices: need n_pop >= {k + 1}, got {n_pop}")
    excluded = [np.arange(n_pop, dtype=np.int64)]  # per row, ascending across the list
    out = np.empty((n_pop, k), dtype=np.int64)
    # One draw for all k columns: floor(u * m) is uniform on [0, m) for u ~ U[0, 1)
    # (the minimum only guards against round-off reaching m).
    m = n_pop - 1 - np.arange(k)
    draws = np.minimum((rng.random((n_pop, k)) * m).astype(np.int64), m - 1)
    for j in range(k):
        c = draws[:, j]
        for e in excluded:
            c += c >= e
        out[:, j] = c
        merged, carry = [], c
        for e in excluded:  # insert c keeping every row sorted
            merged.append(np.minimum(e, carry))
            carry = np.maximum(e, carry)
        excluded = [*merged, carry]
    return out


def rand1_mutation(population: np.ndarray, idx: np.ndarray, F: float) -> np.ndarray:
    """DE/rand/1 mutant vectors ``v_i = x_r1 + F (x_r2 - x_r3)``.

    ===========  =================  =========================================
    Name         Shape              Meaning
    ===========  =================  =========================================
    population   (n_pop, n_var)     parent vectors (normalised box)
    idx          (n_pop, 3) int     ``r1, r2, r3`` per target
    F            scalar             mutation (differential weight) factor
    returns      (n_pop, n_var)     mutants (may leave the normalised box)
    ===========  =================  =========================================
    """
    return population[idx[:, 0]] + F * (population[idx[:, 1]] - population[idx[:, 2]])


def binomial_crossover(
    target: np.ndarray, mutant: np.ndarray, CR: float, r: np.ndarray, j_rand: np.ndarray
) -> np.ndarray:
    """Binomial crossover: take ``mutant[i, j]`` where ``r[i, j] < CR`` or ``j == j_rand[i]``.

    The forced component ``j_rand`` guarantees the trial differs from its target in at
    least one coordinate (Fig. 3: "the trial vector takes at least one value of v").

    =======  ===============  ==============================================
    Name     Shape            Meaning
    =======  ===============  ==============================================
    target   (n_pop, n_var)   current vectors ``x_i``
    mutant   (n_pop, n_var)   mutant vectors ``v_i``
    CR       scalar           crossover probability in [0, 1]
    r        (n_pop, n_var)   uniform [0, 1) draws
    j_rand   (n_pop,) int     forced mutant component per row
    returns  (n_pop, n_var)   trial vectors ``u_i``
    =======  ===============  ==============================================
    """
    take = r < CR
    take[np.arange(target.shape[0]), j_rand] = True
    return np.where(take, mutant, target)


def greedy_selection(
    population: np.ndarray, fitness: np.ndarray, trial: np.ndarray, f_trial: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one survivor selection: the trial replaces its target iff ``f(u) < f(x)``.

    Strict ``<`` as in Fig. 3 of the paper (scipy uses ``<=``). Returns new arrays
    ``(population, fitness)``; the inputs are not modified.
    """
    better = f_trial < fitness
    return (
        np.where(better[:, None], trial, population),
        np.where(better, f_trial, fitness),
    )


# --------------------------------------------------------------------------- state + config


@dataclass(frozen=True, eq=False)
class DEState:
    """State of a DE run (a value: ``tell`` returns a new one).

    ==========  =================  ==================================================
    Field       Shape / type       Meaning
    ==========  =================  ==================================================
    bounds      Bounds             search box
    rng         Generator          private random stream
    population  (n_pop, n_var)     parent vectors, normalised box
    fitness     (n_pop,)           their fitness (``inf`` before the first ``tell``)
    trial       (n_pop, n_var)     vectors the next ``ask`` returns, normalised box
    best_x      (n_var,)           best point so far, problem coordinates
    best_f      float              its fitness
    nfev        int                evaluations so far
    nit         int                iterations so far (initial evaluation included)
    history     (nit,)             best fitness after each iteration
    ==========  =================  ==================================================
    """

    bounds: Bounds
    rng: np.random.Generator
    population: np.ndarray
    fitness: np.ndarray
    trial: np.ndarray
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray


@dataclass(frozen=True)
class DE:
    """Differential evolution, DE/rand/1/bin, as in Fig. 3 of Baldo et al. (2023).

    ===========  ==================  =======  ===============================================
    Parameter    Type                Default  Source / meaning
    ===========  ==================  =======  ===============================================
    pop_size     int >= 4            50       population size ``N``. Storn & Price (1997)
                                              suggest 5-10 x n_var (40-80 for the 8-D fault
                                              vector); 50 matches the pack size the paper
                                              uses for GWO, so all three algorithms cost the
                                              same per iteration
    F            float in (0, 2]     0.5      mutation factor; 0.5 is Storn & Price's (1997)
                 or (F_min, F_max)            recommended start; the paper allows [0, 2].
                                              A pair draws F uniformly in [F_min, F_max]
                                              once per generation ("dither", Das et al.
                                              2005; scipy's ``mutation=(0.5, 1)``)
    CR           float in [0, 1]     0.9      crossover probability; 0.9 is Storn & Price's
                                              choice for fast convergence on non-separable
                                              problems (the fault parameters interact)
    max_iter     int >= 1            200      iteration budget of
                                              :meth:`default_termination`; the paper gives
                                              none for DE, 200 matches its PSO budget
    ===========  ==================  =======  ===============================================

    The default termination is ``MaxIterations(max_iter) | StallTolerance(1e-9, 50)``:
    the paper's 1e-9 tolerance, with a patience of 50 iterations because rand/1/bin's
    best member can stay flat for long stretches and then improve again (on 8-D
    Rastrigin, median over 12 seeds: patience 20 stops near iteration 58 at f = 29,
    patience 50 near iteration 117 at f = 25, the full 200 iterations reach 20; on sphere
    and Rosenbrock 50 loses nothing). The first ``ask`` returns the uniformly random
    initial population ("Create NxD random individuals", Fig. 3), evaluated as
    iteration 1.
    """

    pop_size: int = 50
    F: float | tuple[float, float] = 0.5
    CR: float = 0.9
    max_iter: int = 200

    name: ClassVar[str] = "de"

    def __post_init__(self) -> None:
        check_int("DE", "pop_size", self.pop_size, 4, " (rand/1 needs three vectors besides the target)")
        object.__setattr__(self, "pop_size", int(self.pop_size))
        F = self.F
        if isinstance(F, (tuple, list, np.ndarray)):
            if len(F) != 2:
                raise ValueError(f"DE: F must be a number in (0, 2] or a pair (F_min, F_max), got {F!r}")
            lo = check_real("DE", "F_min", F[0], 0.0, 2.0, lo_open=True)
            hi = check_real("DE", "F_max", F[1], 0.0, 2.0, lo_open=True)
            if lo > hi:
                raise ValueError(f"DE: F pair must have F_min <= F_max, got {F!r}")
            object.__setattr__(self, "F", (lo, hi))
        else:
            object.__setattr__(self, "F", check_real("DE", "F", F, 0.0, 2.0, lo_open=True))
        object.__setattr__(self, "CR", check_real("DE", "CR", self.CR, 0.0, 1.0))
        object.__setattr__(self, "max_iter", check_int("DE", "max_iter", self.max_iter, 1))

    def default_termination(self) -> Termination:
        """``MaxIterations(max_iter) | StallTolerance(1e-9, patience=50)``."""
        return MaxIterations(self.max_iter) | StallTolerance(1e-9, 50)

    def init(self, bounds: Any, rng: np.random.Generator) -> DEState:
        """Draw the uniform initial population; it is what the first ``ask`` returns."""
        bounds = as_bounds(bounds)
        rng = child_rng(rng)
        pop = rng.random((self.pop_size, bounds.n_var))
        return DEState(
            bounds=bounds,
            rng=rng,
            population=frozen(pop),
            fitness=frozen(np.full(self.pop_size, np.inf)),
            trial=frozen(pop.copy()),
            **start(bounds),
        )

    def ask(self, state: DEState) -> np.ndarray:
        """The trial population in problem coordinates, shape (pop_size, n_var)."""
        return state.bounds.from_normalized(state.trial)

    def tell(self, state: DEState, X: np.ndarray, y: np.ndarray) -> DEState:
        """Greedy selection of the evaluated trials, then breed the next trials.

        The first call (initial population vs. ``inf`` placeholders) simply adopts the
        evaluated initial population.
        """
        X, U, y = check_told(state, X, y, self.pop_size)
        pop, fit = greedy_selection(state.population, state.fitness, U, y)
        rng = fork_rng(state.rng)
        F = self.F if isinstance(self.F, float) else rng.uniform(self.F[0], self.F[1])
        idx = distinct_indices(rng, self.pop_size, 3)
        mutant = np.clip(rand1_mutation(pop, idx, F), 0.0, 1.0)
        r = rng.random(pop.shape)
        j_rand = rng.integers(0, pop.shape[1], size=self.pop_size)
        trial = binomial_crossover(pop, mutant, self.CR, r, j_rand)
        return dataclasses.replace(
            state,
            rng=rng,
            population=frozen(pop),
            fitness=frozen(fit),
            trial=frozen(trial),
            **advance(state, X, y),
        )
