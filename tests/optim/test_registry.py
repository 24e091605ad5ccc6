"""Optimizers and solvers of one's own by name (:func:`emaphm.optim.register`, issue 34):
what may be registered, what the name builds, and what is refused with the fix."""

from __future__ import annotations

import numpy as np
import pytest

from emaphm.optim import PSO, get_optimizer, lookup, register, registered, registered_kind, unregister
from emaphm.optim.lsq import MultistartLeastSquares


class WidePSO(PSO):
    """An optimizer class of one's own (a PSO with another name)."""

    name = "widepso"


def fixed_point(objective, bounds, rng):
    lo, hi = bounds
    return 0.5 * (lo + hi)


@pytest.fixture
def clean_registry():
    before = registered()
    yield
    for name in set(registered()) - set(before):
        unregister(name)


def test_each_kind_registers_and_builds(clean_registry):
    register("widepso", WidePSO)
    register("mine-pso", PSO(pop_size=12))
    register("fixed", fixed_point)
    register("lsq2", MultistartLeastSquares(restarts=0))
    kinds = {n: registered_kind(n) for n in ("widepso", "mine-pso", "fixed", "lsq2", "nothing")}
    assert kinds == {"widepso": "optimizer class", "mine-pso": "optimizer", "fixed": "function",
                     "lsq2": "solver", "nothing": None}
    assert get_optimizer("widepso", pop_size=8) == WidePSO(pop_size=8)
    assert get_optimizer("mine-pso") is lookup("mine-pso")
    with pytest.raises(ValueError, match="takes no options"):
        get_optimizer("mine-pso", pop_size=3)
    with pytest.raises(ValueError, match="registered function, not an optimizer"):
        get_optimizer("fixed")
    register("fixed", fixed_point)                    # the same again: harmless


def test_misuse_is_refused_with_the_fix(clean_registry):
    with pytest.raises(ValueError, match="emaphm's own"):
        register("pso", fixed_point)
    with pytest.raises(ValueError, match="letters, digits"):
        register("my solver", fixed_point)
    with pytest.raises(TypeError, match="no ask/tell optimizer"):
        register("cls", dict)
    with pytest.raises(TypeError, match="neither an optimizer"):
        register("num", 3)
    register("fixed", fixed_point)
    with pytest.raises(ValueError, match="registered already"):
        register("fixed", lambda objective, bounds, rng: bounds[0])
    register("fixed", np.median, replace=True)
    assert lookup("fixed") is np.median
    with pytest.raises(ValueError, match="is not registered .* register it with"):
        lookup("unknown")
    with pytest.raises(KeyError):
        unregister("unknown")
