"""Many traces at once: identify or examine a list of traces on worker processes.

:func:`emaphm.identify.identify` and :func:`emaphm.verdict.examine` given a list (or a
tuple) of traces come here: each trace is identified (examined) as a call of its own would
identify it, with the same settings and the same seed, so a batch gives, trace by trace
and in order, the results of the calls made one after the other. ``workers`` processes
share the traces: this one and ``workers - 1`` of the campaigns'
:class:`~emaphm.campaign.executors.LocalExecutor`, each taking the next trace as it comes
free, so that this process, warm already, works while the others start. Those load the
model kernels once (:func:`~emaphm.campaign.executors.warm_up`) and stay warm for the
next batch of the same size of pool, until :func:`close_pools` (or the process ends).
``workers`` None, 0 or 1: in this process, one after the other.

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
    if workers <= 1 or len(tasks) <= 1:
        return [_one(task) for task in tasks]
    out: list[Any] = [None] * len(tasks)
    for index, value in _shared(tasks, workers - 1):
        out[index] = value
    errors = [(i, v) for i, v in enumerate(out) if isinstance(v, BaseException)]
    if errors:
        i, exc = min(errors, key=lambda e: e[0])
        raise type(exc)(f"trace {i} of the batch: {exc}") if isinstance(exc, ValueError) else exc
    return out


def _local(task: tuple) -> Any:
    try:
        return _one(task)
    except Exception as exc:             # noqa: BLE001 - reported with the trace's index
        return exc


def _shared(tasks: list[tuple], n_pool: int) -> list[tuple[int, Any]]:
    """``(index, result or exception)`` of every task: this process and a kept pool of
    ``n_pool`` workers each take the next task as they come free (a worker holds one at a
    time, and is handed the next the moment it returns one, from the pool's own thread, so
    that it never waits for this process to finish a task of its own). A task a dying
    worker took is run here instead."""
    import threading
    from collections import deque
    from concurrent.futures.process import BrokenProcessPool

    executor = _pool(n_pool)
    pool = executor.kept_pool()
    todo = deque(tasks)
    lock = threading.Lock()
    done: list[tuple[int, Any]] = []
    orphans: list[tuple] = []               # taken by a worker that died
    finished = threading.Semaphore(0)       # one release per task a worker ends
    handed = [0]

    def take(worker: bool) -> tuple | None:
        """The next task (for a worker: counted as handed, in the same lock, so that this
        process, once the list is empty, knows how many to wait for)."""
        with lock:
            if not todo:
                return None
            handed[0] += worker
            return todo.popleft()

    def hand(task: tuple) -> None:
        try:
            fut = pool.submit(_one, task)
        except (BrokenProcessPool, RuntimeError):
            with lock:
                orphans.append(task)
            finished.release()
            return
        fut.add_done_callback(lambda f, task=task: ended(f, task))

    def ended(fut: Any, task: tuple) -> None:
        try:
            value = fut.result()
        except BrokenProcessPool:
            with lock:
                orphans.append(task)
            finished.release()
            return
        except Exception as exc:            # noqa: BLE001 - the task's own failure
            value = exc
        with lock:
            done.append((task[0], value))
        nxt = take(True)
        if nxt is not None:
            hand(nxt)
        finished.release()

    for _ in range(n_pool):
        task = take(True)
        if task is None:
            break
        hand(task)
    ours: list[tuple[int, Any]] = []
    while (task := take(False)) is not None:
        ours.append((task[0], _local(task)))
    for _ in range(handed[0]):              # every task a worker was handed has ended
        finished.acquire()
    ours += [(t[0], _local(t)) for t in orphans]
    if orphans:                             # broken: the next batch starts a new pool
        executor.close()
    return done + ours


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
