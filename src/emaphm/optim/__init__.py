"""Box-constrained metaheuristics with an ask/tell interface: DE, PSO and GWO.

The optimizers know nothing about actuators: they minimise a batch objective
``f(X) -> y`` (X: (n_pop, n_var) in problem coordinates, y: (n_pop,); NaN/inf count as worst)
over a box ``(lo, hi)``.

>>> import numpy as np
>>> from emaphm.optim import minimize, get_optimizer, MaxIterations
>>> sphere = lambda X: np.sum(X**2, axis=1)
>>> res = minimize(sphere, ([-5] * 4, [5] * 4), get_optimizer("pso"), seed=1,
...                termination=MaxIterations(100))
>>> res.fun < 1e-6, res.nit, res.reason
(True, 100, 'max_iterations')

See :mod:`emaphm.optim.base` for the conventions (normalised coordinates, clipping,
iteration counting) and each algorithm's class docstring for its defaults and sources.
"""

from __future__ import annotations

from typing import Any

from .base import (
    AnyOf,
    Bounds,
    MaxEvaluations,
    MaxIterations,
    Optimizer,
    OptimizeResult,
    StallTolerance,
    Termination,
    WallClock,
    as_bounds,
    minimize,
    resume,
)
from .baselines import BASELINES, CMAES, ScipyDE
from .de import DE
from .gwo import GWO
from .pso import PSO
from .registry import lookup, register, registered, registered_kind, unregister

__all__ = [
    "ALGORITHMS",
    "ALL_ALGORITHMS",
    "BASELINES",
    "CMAES",
    "ScipyDE",
    "DE",
    "GWO",
    "PSO",
    "AnyOf",
    "Bounds",
    "MaxEvaluations",
    "MaxIterations",
    "OptimizeResult",
    "Optimizer",
    "StallTolerance",
    "Termination",
    "WallClock",
    "as_bounds",
    "get_optimizer",
    "minimize",
    "resume",
    "register",
    "unregister",
    "registered",
    "registered_kind",
    "lookup",
]

#: The paper's three optimizers by short name (the conformance suite runs on these).
ALGORITHMS: dict[str, type] = {"de": DE, "pso": PSO, "gwo": GWO}

#: Everything :func:`get_optimizer` knows: the paper's three and the library baselines
#: ("scipy-de", "cmaes", :mod:`emaphm.optim.baselines`).
ALL_ALGORITHMS: dict[str, type] = {**ALGORITHMS, **BASELINES}


def get_optimizer(name: str, **kw: Any) -> Optimizer:
    """Build the optimizer registered under ``name`` with options ``kw``.

    Parameters
    ----------
    name : str
        One of ``ALL_ALGORITHMS`` ("de", "gwo", "pso", "scipy-de", "cmaes"), or a name
        :func:`register` gave an optimizer class (built with ``kw``) or an optimizer
        (returned as it is; it takes no options).
    **kw
        Passed to the optimizer's constructor (e.g. ``pop_size=30``).

    Raises
    ------
    ValueError
        ``unknown algorithm 'x'; choose one of cmaes, de, gwo, pso, scipy-de`` for an unknown name, or
        the optimizer's own message for an invalid option.
    """
    kind = registered_kind(name)
    if kind == "optimizer class":
        return lookup(name)(**kw)
    if kind == "optimizer":
        if kw:
            raise ValueError(f"{name!r} is a registered optimizer and takes no options, got "
                             f"{kw}; register its class to build it with options")
        return lookup(name)
    try:
        cls = ALL_ALGORITHMS[name]
    except (KeyError, TypeError):
        own = [n for n, _ in sorted(registered().items())
               if registered_kind(n) in ("optimizer class", "optimizer")]
        raise ValueError(
            f"unknown algorithm {name!r}; choose one of {', '.join(sorted(ALL_ALGORITHMS) + own)}"
            + ("" if kind is None else f" ({name!r} is a registered {kind}, not an optimizer)")
        ) from None
    return cls(**kw)
