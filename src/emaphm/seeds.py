"""The one check of a seed: every random choice of emaphm flows from an explicit seed.

A seed is a non-negative integer (NumPy's too); where a function also takes a
:class:`numpy.random.Generator`, :func:`as_generator` accepts one and advances it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["check_seed", "as_generator"]


def check_seed(seed: Any, what: str = "seed") -> int:
    """``seed`` as an int, or a ValueError that names ``what`` and the fix (a bool, a
    float, a string, None and a negative number are refused)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"{what} must be a non-negative integer, got {seed!r} (randomness "
                         "always flows from an explicit seed, e.g. 0)")
    return int(seed)


def as_generator(seed: Any, what: str = "seed") -> np.random.Generator:
    """A :class:`numpy.random.Generator` from a seed (:func:`check_seed`), or the given
    Generator itself."""
    if isinstance(seed, np.random.Generator):
        return seed
    try:
        seed = check_seed(seed, what)
    except ValueError:
        raise ValueError(f"{what} must be given explicitly as a non-negative integer or a "
                         f"numpy.random.Generator, got {seed!r} (randomness always flows from an "
                         "explicit seed, e.g. 0)") from None
    return np.random.default_rng(seed)
