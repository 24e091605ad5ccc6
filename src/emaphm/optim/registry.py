"""Optimizers and solvers of one's own, by name: :func:`register`.

A registered name works wherever a built-in one does: :func:`emaphm.optim.get_optimizer`
(an optimizer), and above this package :func:`emaphm.identify.identify`,
:class:`emaphm.identify.IdentificationConfig`, campaign specs and stores, the health
history's inspections and the command line's ``--algorithm`` within the process that
registered it. Results made with it name it, so they round-trip by name.

What may be registered, and what the name then builds:

==================  ===========================================================
object              the name gives
==================  ===========================================================
an optimizer class  instances built with the name's ``options`` (ask/tell,
                    :class:`emaphm.optim.Optimizer`), polished and restarted as
                    the paper's three are
an optimizer        that optimizer (no options), polished and restarted
a solver            that solver (``init``, ``step``, ``result``; no options),
                    under the registered name
a function          ``f(objective, bounds, rng) -> x``
                    (:class:`emaphm.optim.solvers.CallableSolver`), polished and
                    restarted
==================  ===========================================================

The registry belongs to the process. Campaigns send the registered objects they use to
their worker processes with each run (they are pickled: register a module-level function
or class, not a lambda or a closure, to run it in a process pool).
"""

from __future__ import annotations

import re
from typing import Any

from .base import Optimizer

__all__ = ["register", "unregister", "registered", "registered_kind", "lookup", "RESERVED",
           "Renamed"]

#: Names emaphm gives itself: the default least-squares pipeline and the optimizers of
#: :data:`emaphm.optim.ALL_ALGORITHMS`; none of them can be registered.
RESERVED = frozenset({"lsq", "de", "pso", "gwo", "scipy-de", "cmaes"})

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")
_REGISTRY: dict[str, Any] = {}


def registered_kind(name: Any) -> str | None:
    """``"optimizer class"``, ``"optimizer"``, ``"solver"`` or ``"function"`` for a
    registered name; None for any other."""
    obj = _REGISTRY.get(name) if isinstance(name, str) else None
    return None if obj is None else _kind(obj)


def _kind(obj: Any) -> str:
    if isinstance(obj, type):
        if all(hasattr(obj, m) for m in ("init", "ask", "tell")):
            return "optimizer class"
        raise TypeError(f"register: the class {obj.__name__} is no ask/tell optimizer (init, "
                        "ask, tell); register an instance of a solver (init, step, result), an "
                        "optimizer class, or a function f(objective, bounds, rng) -> x")
    if all(hasattr(obj, m) for m in ("init", "step", "result")):
        return "solver"
    if isinstance(obj, Optimizer):
        return "optimizer"
    if callable(obj):
        return "function"
    raise TypeError(f"register: {type(obj).__name__} is neither an optimizer (class or "
                    "instance), a solver (init, step, result) nor a function "
                    "f(objective, bounds, rng) -> x")


def register(name: str, obj: Any, *, replace: bool = False) -> None:
    """Make ``obj`` selectable as ``name`` (see the module docstring for what ``obj`` may
    be). ``name``: letters, digits and ``_ . + -``, not one of :data:`RESERVED`.
    Registering the same object again is harmless; another object under a name taken is
    a ValueError unless ``replace``."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"register: the name {name!r} must be letters, digits and _ . + - "
                         "(no spaces or slashes), starting with a letter or digit")
    if name in RESERVED:
        raise ValueError(f"register: {name!r} is emaphm's own; choose another name "
                         f"(taken: {', '.join(sorted(RESERVED))})")
    _kind(obj)
    old = _REGISTRY.get(name)
    if old is not None and old is not obj and not replace:
        raise ValueError(f"register: {name!r} is registered already (to {old!r}); "
                         "unregister it first, or pass replace=True")
    _REGISTRY[name] = obj


def unregister(name: str) -> None:
    """Forget ``name`` (a KeyError for a name not registered)."""
    if name not in _REGISTRY:
        raise KeyError(f"{name!r} is not registered")
    del _REGISTRY[name]


def registered() -> dict[str, Any]:
    """A copy of the registry: name -> object."""
    return dict(_REGISTRY)


def lookup(name: str) -> Any:
    """The object registered as ``name`` (a ValueError that lists the names otherwise)."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        known = ", ".join(sorted(_REGISTRY)) or "none"
        raise ValueError(f"{name!r} is not registered (registered: {known}); register it with "
                         "emaphm.optim.register(name, obj) in this process") from None


class Renamed:
    """A solver under another name (a registered solver under its registered name): every
    attribute is the solver's but ``name``."""

    def __init__(self, solver: Any, name: str) -> None:
        self.solver, self.name = solver, name

    def __getattr__(self, attr: str) -> Any:
        return getattr(self.solver, attr)

    def init(self, problem: Any, termination: Any, seed: int) -> Any:
        return self.solver.init(problem, termination, seed)

    def step(self, problem: Any, state: Any, callback: Any = None) -> Any:
        return self.solver.step(problem, state, callback)

    def result(self, state: Any) -> Any:
        return self.solver.result(state)

    def __reduce__(self) -> tuple:
        return (Renamed, (self.solver, self.name))
