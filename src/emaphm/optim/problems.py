"""Standard test functions in batch form, with their known optima.

``f(X) -> y`` with ``X`` of shape (..., n_var): the same contract as the
objectives the optimizers see. Used by the conformance tests, the cross-checks
against other libraries and ``benchmarks/bench_optim.py``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sphere", "rastrigin", "rosenbrock", "TEST_PROBLEMS", "standard_box"]


def sphere(X: np.ndarray) -> np.ndarray:
    """Sphere, minimum 0 at x = 0."""
    X = np.asarray(X, dtype=float)
    return np.sum(X**2, axis=-1)


def rastrigin(X: np.ndarray) -> np.ndarray:
    """Rastrigin (A = 10), minimum 0 at x = 0; about 10^n local minima on [-5.12, 5.12]^n."""
    X = np.asarray(X, dtype=float)
    return 10.0 * X.shape[-1] + np.sum(X**2 - 10.0 * np.cos(2.0 * np.pi * X), axis=-1)


def rosenbrock(X: np.ndarray) -> np.ndarray:
    """Rosenbrock, minimum 0 at x = (1, ..., 1); for n = 8 a local minimum f ~ 3.99 lies
    near (-1, 1, ..., 1)."""
    X = np.asarray(X, dtype=float)
    return np.sum(100.0 * (X[..., 1:] - X[..., :-1] ** 2) ** 2 + (1.0 - X[..., :-1]) ** 2, axis=-1)


#: name -> (function, standard box (lo, hi) per variable, minimum value, minimiser per variable)
TEST_PROBLEMS = {
    "sphere": (sphere, (-5.12, 5.12), 0.0, 0.0),
    "rastrigin": (rastrigin, (-5.12, 5.12), 0.0, 0.0),
    "rosenbrock": (rosenbrock, (-5.0, 10.0), 0.0, 1.0),
}


def standard_box(name: str, n_var: int) -> tuple[list[float], list[float]]:
    """The usual search box of a test problem in ``n_var`` dimensions."""
    lo, hi = TEST_PROBLEMS[name][1]
    return [lo] * n_var, [hi] * n_var
