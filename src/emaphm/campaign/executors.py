"""Where the runs of a campaign execute: in-process, a local process pool, or Dask.

An executor has one method::

    map_unordered(fn, items) -> iterator of (item, fn(item))     as each one finishes

An exception raised for one item (a worker that died, say) is yielded in place of its
value and the others go on. Closing the iterator early (``close()``, or an exception such
as ``KeyboardInterrupt`` in the consumer) cancels the work not yet started. The runner
commits each result as it arrives, so whatever executor runs them, runs are stored one
by one.

=================  ===========================================================================
executor           what it does
=================  ===========================================================================
SerialExecutor     runs in this process, one after the other (debugging, ``--workers 0``)
LocalExecutor      a ``concurrent.futures.ProcessPoolExecutor`` over all cores by default
                   (spawned workers; no service to start)
DaskExecutor       an existing ``dask.distributed`` cluster (scheduler address or Client);
                   Dask is imported only here, and only when this executor is used
=================  ===========================================================================

Dask sends tasks and results as pickles, and unpickling runs code: connect only to a
scheduler you trust, on a network you trust, or over TLS (``tls://`` with certificates from
Dask's configuration, ``distributed.comm.tls.*``; see docs/campaigns.md).

Every worker process is warmed once (:func:`warm_up`: the Numba kernels of both models
are loaded from their on-disk cache, or compiled if there is none, by a tiny
identification) before it takes its first run, so no run pays for compilation and no
run's timing includes it. ``execute_run`` warms as well, idempotently, so a Dask worker
that joins later is warmed by its first run, outside that run's timing.
"""

from __future__ import annotations

import multiprocessing
import os
import re
import signal
import socket
import sys
import threading
import time
from concurrent.futures.process import BrokenProcessPool
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Callable, Iterable, Iterator, Protocol

__all__ = ["DaskExecutor", "Executor", "LocalExecutor", "SerialExecutor", "make_executor", "warm_up",
           "parse_scheduler_address", "DEFAULT_CONNECT_TIMEOUT"]

#: Seconds to wait for a Dask scheduler to accept the connection and answer its handshake.
DEFAULT_CONNECT_TIMEOUT = 10.0
#: The schemes a scheduler address may have: plain TCP, or TCP under TLS.
SCHEDULER_SCHEMES = ("tcp", "tls")
_HOST_PORT = re.compile(r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):(?P<port>\d{1,5})")


def parse_scheduler_address(address: str) -> str:
    """A Dask scheduler address as ``tcp://HOST:PORT`` or ``tls://HOST:PORT``; ``HOST:PORT``
    means TCP. ValueError, naming the problem, for anything else (another scheme such as
    ``inproc://``, which names a scheduler inside one Python process, a missing or bad
    port, a path)."""
    from emaphm._text import shown

    if not isinstance(address, str) or not address.strip():
        raise ValueError("the scheduler address is empty; give tcp://HOST:PORT, e.g. "
                         "tcp://10.0.0.1:8786")
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    scheme = scheme.lower()
    if scheme not in SCHEDULER_SCHEMES:
        why = (" (an inproc:// address names a scheduler inside one Python process, which a "
               "command cannot reach; start one with `dask scheduler` or use --workers)"
               if scheme == "inproc" else "")
        raise ValueError(f"scheduler address {shown(address)}: scheme {scheme}:// is not "
                         f"supported{why}; give tcp://HOST:PORT or tls://HOST:PORT")
    m = _HOST_PORT.fullmatch(rest)
    if not m:
        raise ValueError(f"scheduler address {shown(address)} is not HOST:PORT after "
                         f"{scheme}://; give e.g. {scheme}://10.0.0.1:8786 (the address "
                         "`dask scheduler` prints)")
    port = int(m.group("port"))
    if not 1 <= port <= 65535:
        raise ValueError(f"scheduler address {shown(address)}: port {port} is outside 1-65535")
    return f"{scheme}://{m.group('host')}:{port}"

_WARM = False


def warm_up() -> float:
    """Load (or compile) the model kernels in this process once; returns the seconds spent
    (0 when already warm)."""
    global _WARM
    if _WARM:
        return 0.0
    from emaphm.identify import IdentificationConfig, identify
    from emaphm.simulate import simulate

    t0 = time.perf_counter()
    trace = simulate(scenario="nominal")
    identify(trace, IdentificationConfig("pso", options={"pop_size": 4}, budget=1), seed=0)
    _WARM = True
    return time.perf_counter() - t0


def _exit_with_parent(parent: int, period_s: float = 0.5) -> None:
    """End this worker when its parent process dies, even by SIGKILL (which no handler of
    the parent sees): on Linux the kernel's parent-death signal, everywhere a daemon
    thread that notices the worker being re-parented."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL, 0, 0, 0)        # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:                             # it died before we got here
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(period_s)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="emaphm-parent-watch", daemon=True).start()


def _init_worker(parent: int | None = None, warm: bool = True) -> None:
    """Process-pool initializer: exit with the parent, leave Ctrl-C to it, then warm up
    (the model kernels; ``warm=False``: work that runs none, the fleet site's drawing)."""
    if parent is not None:
        _exit_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if warm:
        warm_up()


class Executor(Protocol):
    """Runs ``fn`` over ``items``, yielding ``(item, result or exception)`` as they finish."""

    def map_unordered(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Any]]: ...


class SerialExecutor:
    """Run every item in this process, in order."""

    workers = 0

    def map_unordered(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        for item in items:
            try:
                value = fn(item)
            except Exception as exc:          # noqa: BLE001 - yielded as a value
                value = exc
            yield item, value

    def describe(self) -> str:
        return "in-process (serial)"


class LocalExecutor:
    """A pool of worker processes on this machine.

    ===========  =======================================================================
    Parameter    Meaning
    ===========  =======================================================================
    workers      number of processes (default ``os.cpu_count()``); each runs one
                 identification at a time on one core
    mp_context   multiprocessing start method (default ``"spawn"``: workers start clean,
                 safe whatever threads the parent runs; each imports emaphm once)
    ===========  =======================================================================

    Workers ignore SIGINT: Ctrl-C reaches the parent, which stops submitting and cancels
    the pending runs; runs already executing finish in the background and are discarded.

    ``keep=True`` keeps the pool (its warm workers) from one :meth:`map_unordered` to the
    next, until :meth:`close` (or the end of a ``with`` block); by default each call starts
    a pool of at most as many workers as it has items and shuts it down at its end.
    ``warm=False``: the workers load no model kernel first (work that runs none: the fleet
    site's pages and figures).
    """

    def __init__(self, workers: int | None = None, *, mp_context: str = "spawn",
                 keep: bool = False, warm: bool = True) -> None:
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise ValueError(f"workers must be a positive integer, got {workers!r}")
        self.workers = workers or os.cpu_count() or 1
        self.mp_context = mp_context
        self.keep = bool(keep)
        self.warm = bool(warm)
        self._pool: ProcessPoolExecutor | None = None

    def describe(self) -> str:
        return f"local pool of {self.workers} process{'es' if self.workers != 1 else ''}"

    def close(self) -> None:
        """Shut a kept pool down (its workers end); the next call starts a new one."""
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> "LocalExecutor":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def kept_pool(self) -> ProcessPoolExecutor:
        """The kept pool itself (``keep=True``; started on first use): for a caller that
        hands out its own work, one item at a time (:mod:`emaphm.batch`)."""
        if not self.keep:
            raise ValueError("kept_pool() is for a LocalExecutor(keep=True)")
        return self._new_pool(self.workers)

    def _new_pool(self, n_items: int) -> ProcessPoolExecutor:
        if self.keep and self._pool is not None:
            return self._pool
        pool = ProcessPoolExecutor(max_workers=self.workers if self.keep else min(self.workers, n_items),
                                   mp_context=multiprocessing.get_context(self.mp_context),
                                   initializer=_init_worker, initargs=(os.getpid(), self.warm))
        if self.keep:
            self._pool = pool
        return pool

    def _drop(self, pool: ProcessPoolExecutor, wait: bool) -> None:
        """Shut ``pool`` down (a kept one only when it broke: ``wait`` False)."""
        if pool is self._pool:
            if wait:
                return
            self._pool = None
        pool.shutdown(wait=wait, cancel_futures=True)

    def map_unordered(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        items = list(items)
        if not items:
            return

        def new_pool() -> ProcessPoolExecutor:
            return self._new_pool(len(items))

        pool = new_pool()
        # Keep at most two runs per worker queued: pending work stays in the parent,
        # where cancelling it is free and certain.
        todo = list(reversed(items))
        running: dict[Future, Any] = {}
        clean = False
        try:
            while todo or running:
                while todo and len(running) < 2 * self.workers:
                    item = todo[-1]
                    try:
                        running[pool.submit(fn, item)] = item
                    except BrokenProcessPool:     # a worker died: the runs in flight fail
                        break
                    todo.pop()
                if not running:                   # the pool broke with nothing in flight
                    self._drop(pool, wait=False)
                    pool = new_pool()
                    continue
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                broken = False
                for fut in done:
                    item = running.pop(fut)
                    try:
                        value = fut.result()
                    except Exception as exc:      # noqa: BLE001 - a broken pool, a pickling error...
                        value = exc
                        broken = broken or isinstance(exc, BrokenProcessPool)
                    yield item, value
                if broken:
                    # a worker died (OOM kill, segfault): every run in flight is lost with
                    # the pool; report them as failures (a rerun retries them) and go on
                    # with a new pool for the rest
                    for fut, item in list(running.items()):
                        yield item, BrokenProcessPool("a worker of the local pool died while "
                                                      "this run was in flight")
                    running.clear()
                    self._drop(pool, wait=False)
                    pool = new_pool()
            clean = True
        finally:
            if not clean and pool is self._pool:    # interrupted: pending work cancelled,
                for fut in running:                 # the kept workers stay
                    fut.cancel()
            else:
                self._drop(pool, wait=clean)


class DaskExecutor:
    """Runs on an existing Dask distributed cluster.

    ``scheduler`` is a scheduler address (``"tcp://host:8786"``, ``"host:8786"`` or
    ``"tls://host:8786"``, checked by :func:`parse_scheduler_address`), then a Client is
    opened for the campaign and closed after it, or a ``distributed.Client`` (left open).
    ``timeout``: seconds to wait for the scheduler to answer (default
    :data:`DEFAULT_CONNECT_TIMEOUT`); a service that does not answer as a Dask scheduler
    within it, or answers something else, is a ValueError naming the address.

    Dask exchanges pickles: connect only to a scheduler you trust. A ``tls://`` address
    uses the certificates of Dask's configuration (``distributed.comm.tls.ca-file``,
    ``.client.cert``, ``.client.key``); or pass a Client built with a ``Security`` object.

    Workers need emaphm installed (same version) and are warmed once each, by a
    :func:`warm_up` task pinned to every worker present at the start (a worker that joins
    later warms itself before its first run). Results come back as they finish.
    """

    def __init__(self, scheduler: Any, *, warm: bool = True, timeout: float | None = None) -> None:
        if isinstance(scheduler, str):
            scheduler = parse_scheduler_address(scheduler)
        timeout = DEFAULT_CONNECT_TIMEOUT if timeout is None else float(timeout)
        if not timeout > 0:
            raise ValueError(f"the connection timeout must be positive seconds, got {timeout!r}")
        try:
            import distributed  # noqa: F401
        except ImportError:
            raise ValueError("a Dask scheduler needs dask.distributed; install it with "
                             "pip install 'emaphm[dask]'") from None
        self.scheduler = scheduler
        self.warm = warm
        self.timeout = timeout
        self.workers = None

    def describe(self) -> str:
        addr = self.scheduler if isinstance(self.scheduler, str) else getattr(self.scheduler, "scheduler", None)
        addr = getattr(addr, "address", addr)
        return f"Dask cluster at {addr}"

    def check(self) -> None:
        """Connect once, so that a wrong address fails before anything is written."""
        client, own = self._client()
        if own:
            client.close()

    def _client(self) -> tuple[Any, bool]:
        if isinstance(self.scheduler, str):
            return _connect(self.scheduler, self.timeout), True
        return self.scheduler, False

    def map_unordered(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        from distributed import as_completed

        items = list(items)
        if not items:
            return
        client, own = self._client()
        futures: list[Any] = []
        try:
            if self.warm:
                # one warm-up task per worker, in its task thread (client.run would block
                # the worker's event loop while the kernels load)
                workers = list(client.scheduler_info()["workers"])
                client.gather([client.submit(warm_up, workers=[w], allow_other_workers=False,
                                             pure=False) for w in workers])
            futures = client.map(fn, items, pure=False)
            item_of = {f.key: it for f, it in zip(futures, items)}
            for fut in as_completed(futures):
                try:
                    value = fut.result()
                except Exception as exc:          # noqa: BLE001 - KilledWorker, lost data...
                    value = exc
                yield item_of[fut.key], value
                fut.release()
        finally:
            pending = [f for f in futures if not f.done()]
            if pending:
                client.cancel(pending)
            if own:
                client.close()


def _probe(address: str, timeout: float) -> None:
    """Ask the service at ``address`` who it is, within ``timeout`` seconds: a ValueError
    naming the address unless a Dask scheduler answers.

    Dask bounds the TCP connection by its own timeout but not the handshake that follows
    (a service that accepts and never answers would hang the command), and a failed
    ``Client`` lingers and complains when it is collected; so the question is asked on a
    bare connection, in an event loop of its own (in a thread: the caller may run one)."""
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    security = Security()
    if address.startswith("tls://") and not security.tls_ca_file:
        raise ValueError(f"{address}: tls:// needs the certificates in Dask's configuration "
                         "(distributed.comm.tls.ca-file, .client.cert and .client.key, e.g. in "
                         "~/.config/dask/distributed.yaml or as DASK_DISTRIBUTED__COMM__TLS__"
                         "CA_FILE=...; see docs/campaigns.md)")
    host, _, port = address.partition("://")[2].rpartition(":")
    try:                      # first whether anything listens there at all
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as exc:
        why = exc.strerror or str(exc) or type(exc).__name__
        raise ValueError(f"cannot reach a Dask scheduler at {address} ({why}); check the "
                         "address and that the scheduler is running") from None

    async def ask() -> Any:
        args = security.get_connection_args("client")   # tls:// certificates from the config
        comm = await connect(address, timeout=timeout, **args)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    box: dict[str, Any] = {}

    def run() -> None:
        try:      # Dask's connect gives up after ``timeout``; the handshake is bounded here
            box["reply"] = asyncio.run(asyncio.wait_for(ask(), timeout + 2.0))
        except BaseException as exc:               # noqa: BLE001 - reported below
            box["error"] = exc

    thread = threading.Thread(target=run, name="emaphm-dask-probe", daemon=True)
    thread.start()
    thread.join(timeout + 5.0)
    exc = box.get("error")
    if thread.is_alive() or isinstance(exc, (asyncio.TimeoutError, TimeoutError)):
        raise ValueError(f"the service at {address} accepted the connection but gave no Dask "
                         f"answer within {timeout:g} s: not a Dask scheduler, or one too busy; "
                         "check the address (the scheduler's port, 8786 by default, not the "
                         "dashboard's 8787), and for tls:// the certificates "
                         "(--connect-timeout to wait longer)")
    if exc is not None:
        cause = exc.__cause__ if exc.__cause__ is not None else exc
        detail = f"{type(cause).__name__}: {str(cause)[:160]}" if str(cause) else type(cause).__name__
        if "timed out trying to connect" in str(exc).lower():
            detail = "it closed or ignored the Dask handshake"
        elif not isinstance(cause, OSError):
            detail = f"it sent bytes that are no Dask message: {detail[:100]}"
        tls = "; a scheduler started with TLS needs tls://" if address.startswith("tcp://") else ""
        raise ValueError(f"the service at {address} did not answer as a Dask scheduler "
                         f"({detail}); check the address (the scheduler's port, 8786 by "
                         f"default){tls}, and that both sides run compatible versions of "
                         "dask.distributed")
    reply = box.get("reply")
    if not (isinstance(reply, dict) and reply.get("type") == "Scheduler"):
        what = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise ValueError(f"the service at {address} is not a Dask scheduler (it says it is a "
                         f"{str(what)[:40]}); give the scheduler's address, e.g. the one "
                         "`dask scheduler` prints")


def _connect(address: str, timeout: float) -> Any:
    """A ``distributed.Client`` of the scheduler at ``address``, asked first (:func:`_probe`)."""
    from distributed import Client

    _probe(address, timeout)
    try:
        return Client(address, timeout=f"{timeout}s")
    except OSError as exc:
        raise ValueError(f"cannot connect to the Dask scheduler at {address} ({exc}); check "
                         "that it is still running") from None


def make_executor(workers: int | None = None, scheduler: Any = None, *,
                  timeout: float | None = None) -> Any:
    """The executor for CLI-style options: a scheduler -> Dask (``timeout``: seconds to
    wait for it); ``workers=0`` -> in-process; otherwise a local pool of ``workers``
    (default all cores)."""
    if scheduler is not None:
        return DaskExecutor(scheduler, timeout=timeout)
    if workers == 0:
        return SerialExecutor()
    return LocalExecutor(workers)
