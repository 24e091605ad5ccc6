"""Particle swarm optimisation, global-best topology (Kennedy & Eberhart 1995; Fig. 4 of
Baldo et al. 2023), with inertia weight (Shi & Eberhart 1998) and velocity clamping.

Every iteration, with ``p_i`` the best point particle ``i`` has visited and ``g`` the
best point of the whole swarm::

    v_i <- w v_i + c1 r1 (p_i - x_i) + c2 r2 (g - x_i)      r1, r2 ~ U[0, 1) per component
    v_i <- clip(v_i, -v_max, v_max)                          velocity clamping
    x_i <- x_i + v_i                                         then clipped to the box

Positions live in the normalised box, so ``v_max`` is a fraction of each variable's range.
A component that would leave the box is clipped to the face and its velocity set to
zero ("absorbing walls", Robinson & Rahmat-Samii 2004), so the particle does not keep
pushing against the wall; the optimum may then sit exactly on a bound.

The update equations are pure module-level functions (random numbers are passed in);
:class:`PSO` only wires them into ``init``/``ask``/``tell``.
"""

from __future__ import annotations

import dataclasses
import math
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

__all__ = ["PSO", "PSOState", "pso_position_update", "pso_velocity_update", "update_personal_best"]


# --------------------------------------------------------------------------- pure updates


def update_personal_best(
    pbest: np.ndarray, pbest_f: np.ndarray, x: np.ndarray, f: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Replace each particle's memory where the new position is strictly better.

    =======  ===============  =====================================
    Name     Shape            Meaning
    =======  ===============  =====================================
    pbest    (n_pop, n_var)   personal best positions (normalised box)
    pbest_f  (n_pop,)         their fitness
    x        (n_pop, n_var)   just-evaluated positions
    f        (n_pop,)         their fitness
    returns                   new ``(pbest, pbest_f)`` arrays
    =======  ===============  =====================================
    """
    better = f < pbest_f
    return np.where(better[:, None], x, pbest), np.where(better, f, pbest_f)


def pso_velocity_update(
    v: np.ndarray,
    x: np.ndarray,
    pbest: np.ndarray,
    gbest: np.ndarray,
    w: float,
    c1: float,
    c2: float,
    r1: np.ndarray,
    r2: np.ndarray,
    v_max: float,
) -> np.ndarray:
    """Inertia + cognitive + social velocity update with clamping to ``[-v_max, v_max]``.

    ``v' = clip(w v + c1 r1 (pbest - x) + c2 r2 (gbest - x), -v_max, v_max)``

    =======  ===============  ===============================================
    Name     Shape            Meaning
    =======  ===============  ===============================================
    v        (n_pop, n_var)   velocities, normalised box per iteration
    x        (n_pop, n_var)   positions, normalised box
    pbest    (n_pop, n_var)   personal best positions
    gbest    (n_var,)         swarm best position
    w        scalar           inertia weight
    c1, c2   scalar           cognitive and social acceleration coefficients
    r1, r2   (n_pop, n_var)   uniform [0, 1) draws
    v_max    scalar           velocity limit, fraction of the range
    returns  (n_pop, n_var)   new velocities
    =======  ===============  ===============================================
    """
    v_new = w * v + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x)
    return np.clip(v_new, -v_max, v_max, out=v_new)


def pso_position_update(x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Move ``x`` by ``v`` inside the normalised box with absorbing walls.

    Returns ``(x', v')``: ``x' = clip(x + v, 0, 1)`` and ``v'`` equal to ``v`` except
    zero in the components that were clipped.
    """
    moved = x + v
    x_new = np.clip(moved, 0.0, 1.0)
    v_new = np.where(x_new == moved, v, 0.0)
    return x_new, v_new


# --------------------------------------------------------------------------- state + config


@dataclass(frozen=True, eq=False)
class PSOState:
    """State of a PSO run (a value: ``tell`` returns a new one).

    ==========  =================  ==================================================
    Field       Shape / type       Meaning
    ==========  =================  ==================================================
    bounds      Bounds             search box
    rng         Generator          private random stream
    position    (n_pop, n_var)     positions the next ``ask`` returns, normalised box
    velocity    (n_pop, n_var)     velocities that moved the swarm there
    pbest       (n_pop, n_var)     personal best positions, normalised box
    pbest_f     (n_pop,)           their fitness (``inf`` before the first ``tell``)
    best_x      (n_var,)           best point so far (swarm best), problem coordinates
    best_f      float              its fitness
    nfev        int                evaluations so far
    nit         int                iterations so far (initial evaluation included)
    history     (nit,)             best fitness after each iteration
    ==========  =================  ==================================================
    """

    bounds: Bounds
    rng: np.random.Generator
    position: np.ndarray
    velocity: np.ndarray
    pbest: np.ndarray
    pbest_f: np.ndarray
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray


@dataclass(frozen=True)
class PSO:
    """Global-best particle swarm optimisation with inertia weight and velocity clamping.

    ===========  ===============  ========  ===============================================
    Parameter    Type             Default   Source / meaning
    ===========  ===============  ========  ===============================================
    pop_size     int >= 2         50        swarm size; the paper gives none for PSO, 50
                                            matches its GWO pack so the algorithms cost
                                            the same per iteration
    w            float in [0, 1)  0.7298    inertia weight: the constriction factor
                                            chi = 0.7298 of Clerc & Kennedy (2002),
                                            phi = 4.1, written in inertia form (Eberhart
                                            & Shi 2000)
    c1           float >= 0       1.49618   cognitive coefficient, chi * phi / 2
                                            (Clerc & Kennedy 2002)
    c2           float >= 0       1.49618   social coefficient, same source
    v_max        float in (0, 1]  0.2       velocity limit as a fraction of each
                                            variable's range; 0.1-0.2 of the range is
                                            the usual recommendation (Eberhart & Shi
                                            2001). Constriction already bounds the swarm;
                                            the clamp only tames the first iterations
    max_iter     int >= 1         200       iteration budget of
                                            :meth:`default_termination`: "200 iterations"
                                            (Baldo et al. 2023, sec. 3.1.2)
    ===========  ===============  ========  ===============================================

    Initial positions are uniform in the box, initial velocities uniform in
    ``[-v_max, v_max]``. The default termination is
    ``MaxIterations(max_iter) | StallTolerance(1e-9, 20)``: the paper stops "until 200
    iterations are reached or until the error between two successive runs is less than
    1e-9"; see :class:`~emaphm.optim.base.StallTolerance` for why the patience is 20 and
    not 1.
    """

    pop_size: int = 50
    w: float = 0.7298
    c1: float = 1.49618
    c2: float = 1.49618
    v_max: float = 0.2
    max_iter: int = 200

    name: ClassVar[str] = "pso"

    def __post_init__(self) -> None:
        object.__setattr__(self, "pop_size", check_int("PSO", "pop_size", self.pop_size, 2))
        object.__setattr__(self, "w", check_real("PSO", "w", self.w, 0.0, 1.0, hi_open=True))
        object.__setattr__(self, "c1", check_real("PSO", "c1", self.c1, 0.0, math.inf, hi_open=True))
        object.__setattr__(self, "c2", check_real("PSO", "c2", self.c2, 0.0, math.inf, hi_open=True))
        if self.c1 + self.c2 == 0.0:
            raise ValueError("PSO: c1 + c2 must be > 0 (otherwise the particles never learn), got 0")
        object.__setattr__(
            self, "v_max", check_real("PSO", "v_max", self.v_max, 0.0, 1.0, lo_open=True)
        )
        object.__setattr__(self, "max_iter", check_int("PSO", "max_iter", self.max_iter, 1))

    def default_termination(self) -> Termination:
        """``MaxIterations(max_iter) | StallTolerance(1e-9, patience=20)``."""
        return MaxIterations(self.max_iter) | StallTolerance(1e-9, 20)

    def init(self, bounds: Any, rng: np.random.Generator) -> PSOState:
        """Uniform positions and velocities; the first ``ask`` returns the positions."""
        bounds = as_bounds(bounds)
        rng = child_rng(rng)
        shape = (self.pop_size, bounds.n_var)
        x = rng.random(shape)
        v = rng.uniform(-self.v_max, self.v_max, size=shape)
        return PSOState(
            bounds=bounds,
            rng=rng,
            position=frozen(x),
            velocity=frozen(v),
            pbest=frozen(x.copy()),
            pbest_f=frozen(np.full(self.pop_size, np.inf)),
            **start(bounds),
        )

    def ask(self, state: PSOState) -> np.ndarray:
        """Current particle positions in problem coordinates, shape (pop_size, n_var)."""
        return state.bounds.from_normalized(state.position)

    def tell(self, state: PSOState, X: np.ndarray, y: np.ndarray) -> PSOState:
        """Update personal and swarm bests from the evaluated positions, then move."""
        X, U, y = check_told(state, X, y, self.pop_size)
        pbest, pbest_f = update_personal_best(state.pbest, state.pbest_f, U, y)
        gbest = pbest[int(np.argmin(pbest_f))]
        rng = fork_rng(state.rng)
        r1 = rng.random(U.shape)
        r2 = rng.random(U.shape)
        v = pso_velocity_update(
            state.velocity, U, pbest, gbest, self.w, self.c1, self.c2, r1, r2, self.v_max
        )
        x, v = pso_position_update(U, v)
        return dataclasses.replace(
            state,
            rng=rng,
            position=frozen(x),
            velocity=frozen(v),
            pbest=frozen(pbest),
            pbest_f=frozen(pbest_f),
            **advance(state, X, y),
        )
