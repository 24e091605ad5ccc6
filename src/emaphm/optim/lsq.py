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

import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from .base import OptimizeResult, as_bounds
from .local import compass_search

__all__ = ["least_squares_batched", "multistart_least_squares", "LSQState", "DIFF_STEPS"]

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


def least_squares_batched(residuals: Callable[[np.ndarray], np.ndarray], x0: Any, bounds: Any, *,
                          diff_step: float | Sequence[float] = 1e-3, max_evals: float = 2000,
                          max_seconds: float = float("inf"), xtol: float = 1e-4,
                          ftol: float = 1e-6, max_nfev: int = 60,
                          callback: Callable[[np.ndarray, float, int, int], bool | None] | None = None,
                          ) -> OptimizeResult:
    """Minimise ``||r(x)||^2`` inside ``bounds`` from ``x0``.

    ==========  ======  ==========================================================
    argument    unit    meaning
    ==========  ======  ==========================================================
    residuals   --      ``R(X)``: (m, n) points -> (m, n_res) residuals, in one call
    x0          --      start, problem units, inside the box
    diff_step   unit    forward-difference step as a fraction of each bound's width
                        (a scalar or one per variable); taken inward at a bound
    max_evals   --      residual evaluations (points) this call may spend
    max_seconds s       wall-clock budget
    xtol, ftol  --      SciPy's tolerances on the step and on the cost reduction
                        (defaults 1e-4, 1e-6: tighter ones cost a sixth more evaluations
                        for a change far below the model's own error)
    max_nfev    --      SciPy's limit on its own calls of ``r`` (steps tried)
    callback    --      ``callback(best_x, best_f, nfev, nit)`` before each Jacobian;
                        True stops (reason ``"callback"``)
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

    def jac(x: np.ndarray) -> np.ndarray:
        r0 = f.at(x)
        history.append(best["f"])
        if callback is not None and callback(best["x"], best["f"], f.nfev, len(history)):
            raise _Stop
        step = np.where(x + h <= b.hi, h, -h)
        R = f.batch(x[None, :] + np.diag(step))
        J = (R - r0[None, :]) / step[:, None]
        J[~np.isfinite(J)] = 0.0               # a diverged neighbour tells nothing
        return J.T

    reason = "converged"
    try:
        r0 = f.at(x0)
        if not np.all(np.isfinite(r0)):
            return OptimizeResult(x=x0, fun=np.inf, nfev=f.nfev, nit=0, history=np.array([np.inf]),
                                  reason="not_finite", elapsed_s=time.perf_counter() - t0,
                                  algorithm="lsq")
        best["x"], best["f"] = x0.copy(), _sse(r0)
        with threadpool_limits(limits=1, user_api="blas"):
            res = least_squares(fun, x0, jac=jac, bounds=(b.lo, b.hi), method="trf",
                                x_scale=b.hi - b.lo, xtol=xtol, ftol=ftol, gtol=1e-12,
                                max_nfev=max_nfev)
        if res.status == 0:
            reason = "max_iterations"
    except _Budget:
        reason = "wall_clock" if time.perf_counter() > f.deadline else "max_evaluations"
    except _Stop:
        reason = "callback"
    history.append(best["f"])
    return OptimizeResult(x=best["x"], fun=float(best["f"]), nfev=f.nfev, nit=len(history) - 1,
                          history=np.minimum.accumulate(np.asarray(history)), reason=reason,
                          elapsed_s=time.perf_counter() - t0, algorithm="lsq")


def multistart_least_squares(residuals: Callable[[np.ndarray], np.ndarray],
                             starts: Sequence[Any], bounds: Any, *, accept: float = 0.0,
                             diff_steps: Sequence[float] = DIFF_STEPS, polish_evals: int = 200,
                             max_evals: float = float("inf"), max_seconds: float = float("inf"),
                             callback: Callable[[LSQState], bool | None] | None = None,
                             fitness: Callable[[np.ndarray], np.ndarray] | None = None,
                             min_gain: float = 0.01, settle: float = float("inf"),
                             charged: Callable[[], int] | None = None,
                             ) -> tuple[OptimizeResult, dict[str, Any]]:
    """Least squares from each of ``starts`` in turn until one reaches ``accept``; the
    best refined and polished.

    1. From each start (in the order given) :func:`least_squares_batched` with step
       ``diff_steps[0]``; stop as soon as the best ``||r||^2 <= accept``, or, once the
       best is at or below ``settle``, when a further start improved it by less than the
       fraction ``min_gain`` (the fit is then limited by the model, not by the basin the
       first start fell into; above ``settle`` every start is tried).
    2. From the best point, one pass with each further step of ``diff_steps`` (a pass
       that does not improve is dropped).
    3. :func:`~emaphm.optim.local.compass_search` of the best point (step 0.02 of the
       box down to 1e-3, at most ``polish_evals`` points): derivative-free, so it
       settles what the differences could not resolve.

    ``max_evals`` and ``max_seconds`` cap everything, with ``charged()`` (if given) the
    evaluations spent outside this function meanwhile, e.g. by a lazy ``starts`` that
    samples the function to choose its points; ``callback(LSQState)`` is called
    before each Jacobian and True stops. ``fitness(X) -> (m,)``, if given, is ``||r||^2``
    computed more cheaply for the polish (without the residual vectors). Returns ``(result, info)``: ``result.reason`` is
    why the search stopped (``"converged"`` or a budget's or the callback's), and
    ``info`` holds ``starts`` (how many were run), ``x_raw, f_raw`` (the best before
    the polish), ``polish_evaluations`` and ``polish_s``.
    """
    t0 = time.perf_counter()
    b = as_bounds(bounds)
    if not starts:
        raise ValueError("multistart_least_squares needs at least one start")
    if len(diff_steps) < 1:
        raise ValueError("diff_steps needs at least one step")
    best: OptimizeResult | None = None
    history: list[float] = []
    nfev = nit = 0
    reason = "converged"
    n_run = 0

    def left() -> tuple[float, float]:
        outside = charged() if charged is not None else 0
        return max_evals - nfev - outside, max_seconds - (time.perf_counter() - t0)

    def run(x: np.ndarray, step: float) -> bool:
        """One pass; False when the search must stop (budget or callback)."""
        nonlocal best, nfev, nit, reason
        evals, seconds = left()
        if evals < b.lo.size + 1 or seconds <= 0:
            reason = "max_evaluations" if evals < b.lo.size + 1 else "wall_clock"
            return False
        def each(x_best: np.ndarray, f_best: float, n_ev: int, n_it: int) -> bool:
            if best is not None and best.fun <= f_best:
                x_best, f_best = best.x, best.fun
            hist = np.minimum.accumulate(np.append(history, f_best))
            return bool(callback(LSQState(x_best, f_best, nfev + n_ev, nit + n_it, hist, n_run)))

        r = least_squares_batched(residuals, x, b, diff_step=step, max_evals=evals,
                                  max_seconds=seconds, callback=None if callback is None else each)
        nfev += r.nfev
        nit += r.nit
        before = np.inf if best is None else best.fun
        if best is None or r.fun < best.fun:
            best = r
        history.extend(np.minimum(r.history, before).tolist())   # best so far at each step
        if r.reason in ("max_evaluations", "wall_clock", "callback"):
            reason = r.reason
            return False
        return True

    going = True
    for x in starts:
        n_run += 1
        before = np.inf if best is None else best.fun
        going = run(np.asarray(x, dtype=float), diff_steps[0])
        if not going or best.fun <= accept or (n_run > 1 and best.fun <= settle
                                                and best.fun > (1 - min_gain) * before):
            break
    if going:
        for step in diff_steps[1:]:
            if not np.isfinite(best.fun) or not run(best.x, step):
                break
    x_raw, f_raw = best.x, best.fun
    pol_evals, pol_s = 0, 0.0
    evals, seconds = left()
    if reason == "converged" and np.isfinite(best.fun) and polish_evals > 0 \
            and evals >= 2 * b.lo.size and seconds > 0:

        def sse(X: np.ndarray) -> np.ndarray:
            R = np.asarray(residuals(X), dtype=float)
            out = np.einsum("ij,ij->i", R, R)
            out[~np.isfinite(out)] = np.inf
            return out

        pol = compass_search(sse if fitness is None else fitness, best.x, b, f0=best.fun, step=0.02, tol=1e-3,
                             max_evals=int(min(polish_evals, evals)), max_seconds=seconds)
        pol_evals, pol_s = pol.nfev, pol.elapsed_s
        nfev += pol.nfev
        history.extend(np.asarray(pol.history[1:], dtype=float).tolist())
        if pol.fun < best.fun:
            best = OptimizeResult(x=pol.x, fun=float(pol.fun), nfev=best.nfev, nit=best.nit,
                                  history=best.history, reason=best.reason,
                                  elapsed_s=best.elapsed_s, algorithm="lsq")
    result = OptimizeResult(x=best.x, fun=float(best.fun), nfev=nfev, nit=nit,
                            history=np.minimum.accumulate(np.asarray(history, dtype=float)),
                            reason=reason, elapsed_s=time.perf_counter() - t0, algorithm="lsq")
    return result, {"starts": n_run, "x_raw": x_raw, "f_raw": float(f_raw),
                    "polish_evaluations": pol_evals, "polish_s": pol_s}
