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

``"ecc-xy-sc"`` (default under the physical fault model): ``"ecc-xy"``, and
the short-circuit components k3..k5 searched as sparse: ``k = SC_SEARCH_MAX
((z - 1/2) / (1/2))^2`` for ``z > 1/2`` and 0 below. A physical fault loop
of a few percent of the turns already moves the currents by amperes, so a
uniform search over [0, 1] puts almost every candidate into shorts far
larger than any real one (where the drive trips and the fitness is flat),
and the chance that a start has all three phases near zero is ``0.05^3``.
Here half of each coordinate's range is a healthy phase and the rest
concentrates near small shorts; the map is continuously differentiable.

``"ecc-xy-sq"`` (the least-squares pipeline's, under the physical fault model):
``"ecc-xy"``, and each short-circuit component searched by the square of its share
of :data:`SC_SEARCH_MAX`, ``k = SC_SEARCH_MAX sqrt(z)``. A fault loop of a fraction
``mu`` of the turns changes the currents in proportion to ``mu^2`` (its current, of
order ``mu``, times its coupling, ``mu``), so in ``z`` the residual is linear near a
healthy phase and a Gauss-Newton step sees the way out of zero, where in ``k`` its
derivative vanishes. Under the paper's fault model (R, L and c0 scaled by ``1 - k``)
the residual is already linear in ``k``, and :func:`least_squares_search` keeps
``"ecc-xy"``.

All maps are vectorised: ``to_k(Z)`` takes (n_pop, 8) in the unit box.
"""

from __future__ import annotations

import numpy as np

from .models.layout import NUISANCE_PARAMETERS

__all__ = ["SEARCH_SPACES", "SC_SEARCH_MAX", "to_k", "from_k", "default_search",
           "least_squares_search", "nuisance_to_box",
           "NUISANCE_RANGE", "nuisance_from_box", "nuisance_text", "nuisance_start"]

SEARCH_SPACES = ("ecc-xy", "k", "ecc-xy-sc", "ecc-xy-sq")

#: Largest shorted fraction the sparse short-circuit search ``"ecc-xy-sc"`` reaches.
SC_SEARCH_MAX = 0.6


#: Range of each parameter searched beside k (relative deviation from the parameters
#: given, calibrated or data sheet; N m for the load; decades for a fault bridge), from
#: :data:`emaphm.models.layout.NUISANCE_PARAMETERS`, where each is listed once with what
#: it is.
NUISANCE_RANGE = {name: (n.lo, n.hi) for name, n in NUISANCE_PARAMETERS.items()}


def nuisance_text(name: str, value: float) -> str:
    """One nuisance value in words: ``"winding resistance +12.0 %"``,
    ``"unreported constant load +0.020 N m"``."""
    n = NUISANCE_PARAMETERS.get(name)
    if n is None:
        return f"{name} {value:+.4g}"
    if n.unit == "relative":
        return f"{n.words} {100 * value:+.1f} %"
    if n.unit == "decades":
        return f"{n.words} x{10.0 ** value:.3g}"
    # a deviation carries its sign; a value that cannot be negative (a loss, a speed) not
    return f"{n.words} {value:{'+' if n.lo < 0 else ''}.3f} {n.unit}"


def nuisance_start(names: tuple[str, ...]) -> np.ndarray:
    """Where a search starts each parameter searched beside k (its nominal 0, or the
    registry's ``start`` where 0 is a flat end of its effect)."""
    return np.array([NUISANCE_PARAMETERS[n].start for n in names], dtype=float)


def nuisance_from_box(Z: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Nuisance values (n_pop, m) from their coordinates in the search box [0, 1]^m."""
    Z = np.atleast_2d(np.asarray(Z, dtype=float))
    lo = np.array([NUISANCE_RANGE[n][0] for n in names])
    hi = np.array([NUISANCE_RANGE[n][1] for n in names])
    return lo + Z * (hi - lo)


def nuisance_to_box(values: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Search-box coordinates (n_pop, m) of nuisance values (n_pop, m): the inverse of
    :func:`nuisance_from_box`."""
    values = np.atleast_2d(np.asarray(values, dtype=float))
    lo = np.array([NUISANCE_RANGE[n][0] for n in names])
    hi = np.array([NUISANCE_RANGE[n][1] for n in names])
    return (values - lo) / (hi - lo)


def default_search(fault_model: str) -> str:
    """The default search space of a fault model."""
    return "ecc-xy-sc" if fault_model == "physical" else "ecc-xy"


def least_squares_search(fault_model: str) -> str:
    """The search space of the least-squares pipeline: one where the residual is
    smooth and its derivative nowhere zero at a healthy component."""
    return "ecc-xy-sq" if fault_model == "physical" else "ecc-xy"


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
    if space == "ecc-xy-sc":
        r = np.maximum(2.0 * Z[:, 2:5] - 1.0, 0.0)
        K[:, 2:5] = SC_SEARCH_MAX * r * r
    elif space == "ecc-xy-sq":
        K[:, 2:5] = SC_SEARCH_MAX * np.sqrt(np.clip(Z[:, 2:5], 0.0, 1.0))
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
    if space == "ecc-xy-sc":
        Z[:, 2:5] = 0.5 + 0.5 * np.sqrt(np.clip(K[:, 2:5] / SC_SEARCH_MAX, 0.0, 1.0))
    elif space == "ecc-xy-sq":
        Z[:, 2:5] = np.clip(K[:, 2:5] / SC_SEARCH_MAX, 0.0, 1.0) ** 2
    return Z


def __getattr__(name: str):
    """The names of version 0.3 (``nuisance_from_unit``, ``nuisance_to_unit``), kept for one
    release with a warning: "unit" means a production unit in emaphm."""
    renamed = {"nuisance_from_unit": nuisance_from_box, "nuisance_to_unit": nuisance_to_box}
    if name in renamed:
        import warnings

        warnings.warn(f"emaphm.search.{name} is renamed {renamed[name].__name__}; the old name "
                      "goes in the next release", DeprecationWarning, stacklevel=2)
        return renamed[name]
    raise AttributeError(f"module 'emaphm.search' has no attribute {name!r}")
