"""Many traces at once: identify or examine a list of traces on worker processes.

:func:`emaphm.identify.identify` and :func:`emaphm.verdict.examine` given a list (or a
tuple) of traces come here: each trace is identified (examined) as a call of its own would
identify it, with the same settings and the same seed, so a batch gives, trace by trace
and in order, the results of the calls made one after the other. ``workers`` processes
(the campaigns' :class:`~emaphm.campaign.executors.LocalExecutor`) share the traces; their
workers load the model kernels once (:func:`~emaphm.campaign.executors.warm_up`) and stay
warm for the next batch of the same size of pool, until :func:`close_pools` (or the
process ends). ``workers`` None, 0 or 1: in this process, one after the other.

An optimizer or solver of one's own goes to the workers with the traces (it is pickled:
a module-level function or class, or a name registered with
:func:`emaphm.optim.register`, whose object is sent along).
"""

from __future__ import annotations

import atexit
from typing import Any, Sequence

__all__ = ["identify_many", "examine_many", "close_pools", "check_workers"]

_POOLS: dict[int, Any] = {}


def check_workers(workers: Any) -> int:
    """``workers`` as a count of processes (None: 0, in this process); a ValueError that
    says what to give otherwise."""
    if workers is None:
        return 0
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise ValueError(f"workers must be a number of processes (an int >= 0; 0 or 1: in this "
                         f"process), got {workers!r}")
    return workers


def _pool(workers: int) -> Any:
    """The kept pool of ``workers`` processes (started on first use, warm after)."""
    from .campaign.executors import LocalExecutor

    pool = _POOLS.get(workers)
    if pool is None:
        pool = _POOLS[workers] = LocalExecutor(workers, keep=True)
    return pool


def close_pools() -> None:
    """End the batches' worker processes (the next batch starts new ones)."""
    while _POOLS:
        _POOLS.popitem()[1].close()


atexit.register(close_pools)


def _plugins(solver: Any) -> dict[str, Any]:
    """The registered algorithms a batch's workers need: the one ``solver`` names."""
    from .optim import registered

    name = solver if isinstance(solver, str) else getattr(solver, "algorithm", None)
    own = registered()
    return {name: own[name]} if isinstance(name, str) and name in own else {}


def _one(task: tuple) -> Any:
    """What a worker does for one trace: ``(index, function name, trace, kwargs, plugins)``."""
    index, what, trace, kw, plugins = task
    from .optim import register

    for name, obj in plugins.items():
        register(name, obj, replace=True)
    if what == "identify":
        from .identify import identify

        return identify(trace, **kw)
    from .verdict import examine

    return examine(trace, **kw)


def _run(what: str, traces: Sequence[Any], kw: dict[str, Any], workers: int,
         plugins: dict[str, Any]) -> list[Any]:
    if kw.get("callback") is not None and workers > 1:
        raise ValueError("a callback watches a search in this process; a batch on worker "
                         "processes takes none (drop callback=, or give workers=0)")
    tasks = [(i, what, t, kw, plugins) for i, t in enumerate(traces)]
    if workers <= 1:
        return [_one(task) for task in tasks]
    out: list[Any] = [None] * len(tasks)
    errors = []
    for task, value in _pool(workers).map_unordered(_one, tasks):
        if isinstance(value, BaseException):
            errors.append((task[0], value))
        out[task[0]] = value
    if errors:
        i, exc = min(errors, key=lambda e: e[0])
        raise type(exc)(f"trace {i} of the batch: {exc}") if isinstance(exc, ValueError) else exc
    return out


def _check(traces: Any) -> list[Any]:
    from .problem import IdentificationProblem
    from .traces import Trace

    traces = list(traces)
    bad = [i for i, t in enumerate(traces) if not isinstance(t, (Trace, IdentificationProblem))]
    if bad:
        raise TypeError(f"a batch is a list of traces (emaphm.traces.Trace); item {bad[0]} is a "
                        f"{type(traces[bad[0]]).__name__}")
    return traces


def identify_many(traces: Sequence[Any], solver: Any, *, workers: Any = None,
                  **kw: Any) -> list[Any]:
    """:func:`emaphm.identify.identify` of each trace (same ``solver``, ``seed`` and
    keywords), on ``workers`` processes; the identifications in the order of ``traces``."""
    traces = _check(traces)
    return _run("identify", traces, {"solver": solver, **kw}, check_workers(workers),
                _plugins(solver))


def examine_many(traces: Sequence[Any], *, workers: Any = None, **kw: Any) -> list[Any]:
    """:func:`emaphm.verdict.examine` of each trace (same ``config``, ``seed`` and
    keywords), on ``workers`` processes; the examinations in the order of ``traces``."""
    traces = _check(traces)
    return _run("examine", traces, kw, check_workers(workers), _plugins(kw.get("config")))
