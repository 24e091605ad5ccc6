"""Local refinement of a metaheuristic's best point: batched compass search.

Metaheuristics find the basin; their last digits come slowly (GWO's pack
collapses early, PSO and DE stall on weakly sensitive directions). Like
scipy's ``differential_evolution(polish=True)``, :func:`compass_search`
polishes the final point, but derivative-free, so it is safe on the
piecewise-smooth fitness that dry friction and backlash produce.

Compass (coordinate pattern) search (Kolda, Lewis & Torczon, SIAM Review 45,
2003): poll the ``2 n`` points ``x +- step e_i`` (clipped into the box) in ONE
batch call, move to the best poll point if it improves, otherwise halve the
step; stop when the step falls below ``tol`` (in normalised coordinates) or the
evaluation budget is spent. Deterministic: no random numbers.
"""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from .base import OptimizeResult, as_bounds, sanitize_fitness

__all__ = ["compass_search"]


def compass_search(objective: Callable[[np.ndarray], np.ndarray], x0: Any, bounds: Any, *,
                   f0: float | None = None, step: float = 0.05, tol: float = 1e-4,
                   max_evals: int = 2000, max_seconds: float = float("inf")) -> OptimizeResult:
    """Polish ``x0`` by compass search inside ``bounds``.

    =========  ======  =========================================================
    argument   unit    meaning
    =========  ======  =========================================================
    x0         --      starting point, problem coordinates, inside the box
    f0         --      its fitness, if known (saves one evaluation)
    step       unit    initial poll step as a fraction of each bound's width
    tol        unit    stop when the step falls below this fraction
    max_evals  --      evaluation budget (a poll that would exceed it is not started)
    max_seconds s      wall-clock budget, checked before each poll
    =========  ======  =========================================================

    Returns an :class:`OptimizeResult` whose ``history`` holds the best
    fitness after each poll and whose ``reason`` is ``"step_tolerance"``,
    ``"max_evaluations"`` or ``"wall_clock"``.
    """
    if not max_seconds > 0:
        raise ValueError(f"compass_search: max_seconds must be > 0, got {max_seconds!r}")
    if not (0 < tol < step <= 1):
        raise ValueError(f"compass_search needs 0 < tol < step <= 1, got tol={tol}, step={step}")
    if isinstance(max_evals, bool) or not isinstance(max_evals, (int, np.integer)) or max_evals < 1:
        raise ValueError(f"compass_search: max_evals must be a positive integer, got {max_evals!r}")
    t0 = time.perf_counter()
    b = as_bounds(bounds)
    u = np.clip(b.to_normalized(np.asarray(x0, dtype=float)[None, :])[0], 0.0, 1.0)
    n = u.size
    nfev = 0
    if f0 is None:
        fu = float(sanitize_fitness(objective(b.from_normalized(u[None, :])), 1)[0])
        nfev += 1
    else:
        fu = float(f0)
    directions = np.vstack([np.eye(n), -np.eye(n)])
    history = [fu]
    reason = "step_tolerance"
    while step >= tol:
        if nfev + 2 * n > max_evals:
            reason = "max_evaluations"
            break
        if time.perf_counter() - t0 >= max_seconds:
            reason = "wall_clock"
            break
        U = np.clip(u + step * directions, 0.0, 1.0)
        f = sanitize_fitness(objective(b.from_normalized(U)), U.shape[0])
        nfev += U.shape[0]
        i = int(np.argmin(f))
        if f[i] < fu:
            u, fu = U[i], float(f[i])
        else:
            step *= 0.5
        history.append(fu)
    return OptimizeResult(x=b.from_normalized(u[None, :])[0], fun=fu, nfev=nfev, nit=len(history) - 1,
                          history=np.asarray(history), reason=reason,
                          elapsed_s=time.perf_counter() - t0, algorithm="compass")
