"""Grey wolf optimizer (Mirjalili, Mirjalili & Lewis 2014; Fig. 5 of Baldo et al. 2023).

Three leaders, alpha, beta and delta, guide the pack. Every wolf ``x`` moves to the
mean of three points, one dictated by each leader ``L``::

    A = 2 a r1 - a,   C = 2 r2                 r1, r2 ~ U[0, 1) per component and leader
    D = |C L - x|,    X_L = L - A D
    x <- (X_alpha + X_beta + X_delta) / 3      then clipped to the box

``a`` decreases linearly from 2 to 0 over ``max_iter`` iterations: ``|A| > 1`` early on
sends wolves away from the leaders (exploration), ``|A| < 1`` late pulls them in.

The hierarchy is updated exactly as in Mirjalili's reference code (GWO.m, which niapy
follows too; clipping to the box is also what that code does): the wolves of the new
pack are visited in order and a wolf with fitness ``f`` becomes

* alpha if ``f < f_alpha``;
* otherwise beta if ``f_alpha < f < f_beta``;
* otherwise delta if ``f_beta < f < f_delta``.

The previous holder of a slot is dropped, not demoted, so alpha is always the best
point so far while beta and delta may be older, worse points. That keeps more spread in
the pack than an elitist "three best so far" archive: over 60 seeds on 8-D Rastrigin
(7,500 evaluations) the reference rule reached a mean of 18.5 with a lower quartile of
8, the archive 22.9 and 18 (Mann-Whitney p = 0.05), with no significant difference on
the sphere or Rosenbrock.

The first pack is ranked instead: alpha, beta and delta are its three best wolves. That
is the paper's "Score each solution; Categorize all solutions" before the main loop
(Fig. 5: "an initial population hierarchy is defined by looking at the fitness function
values"), and what niapy does; GWO.m starts from three empty (``inf``) slots.

Known property, kept on purpose: the move ``|C L - x|`` is not translation invariant
(``C`` scales the leader, not the wolf), so steps stay large unless the leaders sit
near the origin of the coordinates, and GWO is far more precise there than elsewhere
(Niu et al. 2019, "The defect of the grey wolf optimization algorithm and its
verification method"; Camacho-Villalon, Dorigo & Stutzle 2023). Our coordinates are
the normalised box, so that point is ``lo``: for the fault vector, the healthy ``k = 0``,
exactly as in the paper where GWO searched ``k`` directly. On an 8-D sphere centred
mid-box, 150 iterations reach only ~5e-4 (tests/test_optim_conformance.py).

The update equation is a pure module-level function (random numbers are passed in);
:class:`GWO` only wires it into ``init``/``ask``/``tell``.
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
    check_told,
    child_rng,
    fork_rng,
    frozen,
    start,
)

__all__ = ["GWO", "GWOState", "gwo_a", "gwo_position_update", "rank_leaders", "update_leaders"]


# --------------------------------------------------------------------------- pure updates


def gwo_a(t: int, max_iter: int) -> float:
    """Control parameter ``a(t) = 2 (1 - t / max_iter)``, floored at 0.

    ``t`` counts completed iterations (pack evaluations); the move evaluated in iteration
    ``t + 1`` uses ``a(t)``. So ``a`` falls linearly from 2 and reaches 0 exactly at the
    iteration budget: the first move uses ``2 - 2 / max_iter`` and the last one evaluated
    within ``max_iter`` iterations uses ``2 / max_iter``. This is Mirjalili et al.'s
    (2014) schedule counted in evaluations (as niapy does); Mirjalili's MATLAB code
    counts from the move index instead, so its last evaluated move uses ``4 / max_iter``.
    Beyond ``max_iter`` the pack only exploits (a = 0).
    """
    return max(0.0, 2.0 * (1.0 - t / max_iter))


def update_leaders(
    leaders: np.ndarray, leaders_f: np.ndarray, x: np.ndarray, f: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Update alpha, beta and delta from a newly evaluated pack (Mirjalili's GWO.m rule).

    Wolves are visited in order; a wolf replaces alpha if ``f < f_alpha``, else beta if
    ``f_alpha < f < f_beta``, else delta if ``f_beta < f < f_delta``. Ties change
    nothing, and ``inf`` (failed) evaluations never lead. Returns new arrays.

    =========  ===============  =================================================
    Name       Shape            Meaning
    =========  ===============  =================================================
    leaders    (3, n_var)       alpha, beta, delta positions (normalised box)
    leaders_f  (3,)             their fitness (``inf`` while a slot is empty)
    x          (n_pop, n_var)   just-evaluated positions
    f          (n_pop,)         their fitness
    returns                     new ``(leaders, leaders_f)``
    =========  ===============  =================================================
    """
    slot = [-1, -1, -1]  # index into x of each slot's new holder, -1: unchanged
    fa, fb, fd = (float(v) for v in leaders_f)
    for i, fi in enumerate(f.tolist()):
        if fi < fa:
            fa, slot[0] = fi, i
        elif fa < fi < fb:
            fb, slot[1] = fi, i
        elif fb < fi < fd:
            fd, slot[2] = fi, i
    new = leaders.copy()
    for k, i in enumerate(slot):
        if i >= 0:
            new[k] = x[i]
    return new, np.array([fa, fb, fd])


def rank_leaders(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Initial hierarchy: the three best wolves of a pack, best first (ties: lower index).

    =========  ===============  =========================================
    Name       Shape            Meaning
    =========  ===============  =========================================
    x          (n_pop, n_var)   evaluated positions, ``n_pop >= 3``
    f          (n_pop,)         their fitness
    returns                     ``(leaders (3, n_var), leaders_f (3,))``
    =========  ===============  =========================================
    """
    order = np.argsort(f, kind="stable")[:3]
    return x[order].copy(), f[order].copy()


def gwo_position_update(
    x: np.ndarray, leaders: np.ndarray, a: float, r1: np.ndarray, r2: np.ndarray
) -> np.ndarray:
    """Encircling/hunting step of Mirjalili et al. (2014), eqs. 3.1-3.7, vectorised.

    =======  ==================  ================================================
    Name     Shape               Meaning
    =======  ==================  ================================================
    x        (n_pop, n_var)      wolf positions, normalised box
    leaders  (3, n_var)          alpha, beta, delta positions
    a        scalar              control parameter in [0, 2]
    r1, r2   (3, n_pop, n_var)   uniform [0, 1) draws, one set per leader
    returns  (n_pop, n_var)      new positions clipped to the normalised box
    =======  ==================  ================================================
    """
    L = leaders[:, None, :]  # (3, 1, n_var)
    A = 2.0 * a * r1 - a
    C = 2.0 * r2
    D = np.abs(C * L - x[None, :, :])
    x_new = (L - A * D).mean(axis=0)
    return np.clip(x_new, 0.0, 1.0, out=x_new)


# --------------------------------------------------------------------------- state + config


@dataclass(frozen=True, eq=False)
class GWOState:
    """State of a GWO run (a value: ``tell`` returns a new one).

    ==========  =================  ==================================================
    Field       Shape / type       Meaning
    ==========  =================  ==================================================
    bounds      Bounds             search box
    rng         Generator          private random stream
    position    (n_pop, n_var)     wolf positions the next ``ask`` returns, normalised box
    leaders     (3, n_var)         alpha, beta, delta, normalised box
    leaders_f   (3,)               their fitness (``inf`` before the first ``tell``)
    best_x      (n_var,)           best point so far (alpha's), problem coordinates
    best_f      float              its fitness
    nfev        int                evaluations so far
    nit         int                iterations so far (initial evaluation included)
    history     (nit,)             best fitness after each iteration
    ==========  =================  ==================================================
    """

    bounds: Bounds
    rng: np.random.Generator
    position: np.ndarray
    leaders: np.ndarray
    leaders_f: np.ndarray
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray


@dataclass(frozen=True)
class GWO:
    """Grey wolf optimizer with alpha/beta/delta leaders and linearly decreasing ``a``.

    ===========  ==========  =======  =====================================================
    Parameter    Type        Default  Source / meaning
    ===========  ==========  =======  =====================================================
    pop_size     int >= 3    50       pack size: "set to 50 individuals" (Baldo et al.
                                      2023, sec. 3.1.2)
    max_iter     int >= 1    150      iterations over which ``a`` falls from 2 to 0
                                      (Mirjalili et al. 2014), and the budget of
                                      :meth:`default_termination`: "the number of
                                      iterations reached is 150" (Baldo et al. 2023)
    ===========  ==========  =======  =====================================================

    Initial positions are uniform in the box (evaluated as iteration 1, whose three best
    wolves become alpha, beta and delta); see :func:`gwo_a` for the exact ``a`` schedule.

    The default termination is
    ``MaxIterations(max_iter) | StallTolerance(1e-9, max(20, max_iter // 3))`` (patience
    50 for the default 150): the paper stops at 150 iterations "or the tolerance of 1e-9
    is reached within two successive runs". The patience is tied to the ``a`` schedule:
    while ``a > 1`` the wolves are pushed away from the leaders and alpha often stays
    flat for 30-50 iterations (median of the longest plateau over 20 seeds: 27 on 8-D
    sphere, 36 on Rosenbrock). A patience of 20 stopped the sphere at f ~ 1.5 and
    Rosenbrock at f ~ 130 (medians, 12 seeds) against 5e-4 and 7 for the full run; a
    third of the schedule lost nothing. See :class:`~emaphm.optim.base.StallTolerance`
    for why the paper's literal patience of 1 cannot work.
    A custom termination beyond ``max_iter`` keeps ``a = 0``.
    """

    pop_size: int = 50
    max_iter: int = 150

    name: ClassVar[str] = "gwo"

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "pop_size",
            check_int("GWO", "pop_size", self.pop_size, 3, " (alpha, beta and delta)"),
        )
        object.__setattr__(self, "max_iter", check_int("GWO", "max_iter", self.max_iter, 1))

    def default_termination(self) -> Termination:
        """``MaxIterations(max_iter) | StallTolerance(1e-9, max(20, max_iter // 3))``."""
        return MaxIterations(self.max_iter) | StallTolerance(1e-9, max(20, self.max_iter // 3))

    def init(self, bounds: Any, rng: np.random.Generator) -> GWOState:
        """Uniform initial pack; the first ``ask`` returns it."""
        bounds = as_bounds(bounds)
        rng = child_rng(rng)
        x = rng.random((self.pop_size, bounds.n_var))
        return GWOState(
            bounds=bounds,
            rng=rng,
            position=frozen(x),
            leaders=frozen(x[:3].copy()),
            leaders_f=frozen(np.full(3, np.inf)),
            **start(bounds),
        )

    def ask(self, state: GWOState) -> np.ndarray:
        """Current wolf positions in problem coordinates, shape (pop_size, n_var)."""
        return state.bounds.from_normalized(state.position)

    def tell(self, state: GWOState, X: np.ndarray, y: np.ndarray) -> GWOState:
        """Update the hierarchy from the evaluated pack, then move every wolf."""
        X, U, y = check_told(state, X, y, self.pop_size)
        if state.nit == 0:  # categorize the initial pack (Fig. 5)
            leaders, leaders_f = rank_leaders(U, y)
        else:
            leaders, leaders_f = update_leaders(state.leaders, state.leaders_f, U, y)
        rng = fork_rng(state.rng)
        r1 = rng.random((3,) + U.shape)
        r2 = rng.random((3,) + U.shape)
        x = gwo_position_update(U, leaders, gwo_a(state.nit + 1, self.max_iter), r1, r2)
        return dataclasses.replace(
            state,
            rng=rng,
            position=frozen(x),
            leaders=frozen(leaders),
            leaders_f=frozen(leaders_f),
            **advance(state, X, y),
        )
