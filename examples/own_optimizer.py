"""Plug an optimizer of your own into emaphm's identification, without touching emaphm.

Two ways, both through the public protocol (docs/python-api.md):

1. an object with the ask/tell protocol of :class:`emaphm.optim.Optimizer`
   (``init(bounds, rng)``, ``ask(state)``, ``tell(state, X, y)``,
   ``default_termination()``): emaphm runs it, polishes its best point and restarts it
   from a spawned seed when the fit stays far above the trace's noise floor;
2. a plain function ``f(objective, bounds, rng) -> x`` that calls the batch objective
   ``objective(X) -> y`` as it likes.

Both get a valid :class:`emaphm.identify.Identification` and the verdict as ``emaphm
diagnose`` gives it. (The random search is a poor optimizer: it stops far above the
trace's noise floor, and the misfit test says so, ``unexplained``, instead of reading a
wrong fault; the coordinate search finds the friction.) Run: ``python examples/own_optimizer.py`` (``--quick`` for the short
settings the tests use).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from emaphm.identify import identify
from emaphm.optim import MaxEvaluations
from emaphm.simulate import DEFAULT_SENSORS, simulate
from emaphm.verdict import diagnose_identification


@dataclasses.dataclass(frozen=True)
class State:
    bounds: object          # emaphm.optim.Bounds: from_normalized maps [0, 1]^n onto the box
    rng: np.random.Generator
    best_x: np.ndarray
    best_f: float
    nfev: int
    nit: int
    history: np.ndarray


@dataclasses.dataclass(frozen=True)
class RandomSearch:
    """Random search around the best point so far, shrinking: a small ask/tell optimizer.

    States are values: ``tell`` returns a new state and never changes the one it is given
    (it draws from a copy of the state's generator), so emaphm can restart, checkpoint and
    compare runs.
    """

    batch: int = 32
    shrink: float = 0.9
    name: str = "random-search"

    def init(self, bounds, rng):
        n = bounds.n_var
        return State(bounds, rng, bounds.from_normalized(np.full(n, 0.5)), np.inf, 0, 0, np.empty(0))

    def _draw(self, state):
        rng = np.random.Generator(type(state.rng.bit_generator)())
        rng.bit_generator.state = state.rng.bit_generator.state
        width = self.shrink ** state.nit
        centre = state.bounds.to_normalized(state.best_x)
        U = np.clip(centre + width * (rng.random((self.batch, state.bounds.n_var)) - 0.5), 0, 1)
        return rng, state.bounds.from_normalized(U)

    def ask(self, state):
        return self._draw(state)[1]

    def tell(self, state, X, y):
        rng, _ = self._draw(state)
        i = int(np.argmin(y))
        better = y[i] < state.best_f
        best_x = np.array(X[i]) if better else state.best_x
        best_f = float(y[i]) if better else state.best_f
        return dataclasses.replace(state, rng=rng, best_x=best_x, best_f=best_f,
                                   nfev=state.nfev + len(y), nit=state.nit + 1,
                                   history=np.append(state.history, best_f))

    def default_termination(self):
        return MaxEvaluations(3000)


def coordinate_search(objective, bounds, rng):
    """A plain function: polls +-step along every axis from a random start, halving."""
    lo, hi = bounds
    x = lo + (hi - lo) * rng.random(lo.size)
    fx = objective(x[None])[0]
    step = 0.25 * (hi - lo)
    while np.max(step / (hi - lo)) > 1e-3:
        X = np.clip(np.vstack([x + np.diag(step), x - np.diag(step)]), lo, hi)
        f = objective(X)
        i = int(np.argmin(f))
        if f[i] < fx:
            x, fx = X[i], f[i]
        else:
            step = step / 2
    return x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="short settings (the tests')")
    args = ap.parse_args()
    trace = simulate(scenario="friction-high", sensors=DEFAULT_SENSORS, seed=1)
    budget = 600 if args.quick else None
    for solver in (RandomSearch(), coordinate_search):
        ident = identify(trace, solver, seed=0, termination=budget)
        verdict = diagnose_identification(trace, ident)
        print(f"{ident.algorithm}: k1 = {ident.k[0]:.3f} (true {ident.k_true[0]:.2f}), "
              f"{ident.evaluations} evaluations in {ident.elapsed_s:.2f} s, "
              f"Eq. 9 error {ident.error_pct:.1f} %; {verdict.summary()}")


if __name__ == "__main__":
    main()
