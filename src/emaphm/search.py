"""The search space of fault identification: the unit box the optimizers see, mapped onto k.

``"k"``: the paper's choice, the optimizer searches ``k`` itself.

``"ecc-xy"`` (default): the same, except that the eccentricity modulus and
phase ``(k6, k7)`` are searched as the Cartesian components of the
eccentricity vector, ``x = 2 z6 - 1 = k6 cos(phi)``, ``y = 2 z7 - 1 = k6 sin(phi)``
with ``phi = 2 pi (k7 - 0.5)``. In polar form the phase is degenerate at
``k6 = 0`` (every k7 gives the same currents), which leaves a flat valley
where a search stalls and a small true eccentricity is missed; in Cartesian
form the fitness is smooth through zero eccentricity. Points with
``x^2 + y^2 > 1`` are clipped to modulus 1.

Both maps are vectorised: ``to_k(Z)`` takes (n_pop, 8) in the unit box.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SEARCH_SPACES", "to_k", "from_k"]

SEARCH_SPACES = ("ecc-xy", "k")


def _check(space: str) -> None:
    if space not in SEARCH_SPACES:
        raise ValueError(f"unknown search space {space!r}; choose one of {', '.join(SEARCH_SPACES)}")


def to_k(Z: np.ndarray, space: str = "ecc-xy") -> np.ndarray:
    """Fault vectors (n_pop, 8) from search points ``Z`` (n_pop, 8) in [0, 1]^8."""
    _check(space)
    Z = np.atleast_2d(np.asarray(Z, dtype=float))
    if space == "k":
        return Z.copy()
    K = Z.copy()
    x = 2.0 * Z[:, 5] - 1.0
    y = 2.0 * Z[:, 6] - 1.0
    K[:, 5] = np.minimum(np.hypot(x, y), 1.0)
    K[:, 6] = np.where(K[:, 5] > 0.0, np.arctan2(y, x) / (2.0 * np.pi) + 0.5, 0.5)
    return K


def from_k(K: np.ndarray, space: str = "ecc-xy") -> np.ndarray:
    """Search points from fault vectors (the inverse of :func:`to_k` inside the disk)."""
    _check(space)
    K = np.atleast_2d(np.asarray(K, dtype=float))
    if space == "k":
        return K.copy()
    Z = K.copy()
    phi = 2.0 * np.pi * (K[:, 6] - 0.5)
    Z[:, 5] = 0.5 * (1.0 + K[:, 5] * np.cos(phi))
    Z[:, 6] = 0.5 * (1.0 + K[:, 5] * np.sin(phi))
    return Z
