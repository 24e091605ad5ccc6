"""Progress of long work on a stream (stderr): the one facility every command uses.

=====================  ======================================================================
class / function       what it shows
=====================  ======================================================================
:class:`StatusLine`    the mechanics: on a terminal one line redrawn in place (at most ten
                       times a second) and ended by ``close()``; in a Jupyter notebook one
                       output updated in place (IPython's display with a display id); elsewhere
                       (a log, a pipe) nothing, or with ``log=True`` a line at every tenth of
                       a known total
:class:`RunProgress`   runs of a campaign: done / total, failures, elapsed, ETA (logged to a
                       file or pipe too)
:class:`SearchProgress`  an identification, as its ``callback``: iteration, best fitness,
                       evaluations, evaluations per second (a restart is counted)
:class:`CountProgress`   steps of a loop: "simulating trace 3/8", "calibrating: 120 model runs"
:func:`compile_notice`   one line, "compiling the model kernels (first run only)...", the
                       first time Numba compiles a kernel in this process (nothing when the
                       kernels come from its disk cache)
=====================  ======================================================================

Nothing here imports NumPy or a model; :func:`compile_notice` imports Numba's event API
only when entered. The notebook is found as ``tqdm.auto`` finds it, without depending on
tqdm or ipywidgets: IPython already imported and running a kernel
(:func:`notebook_display`); the progress is then plain text in an output that is
updated in place.
"""

from __future__ import annotations

import contextlib
import sys
import time
from typing import Any, Iterator, TextIO

__all__ = ["StatusLine", "RunProgress", "SearchProgress", "CountProgress", "compile_notice",
           "COMPILE_NOTICE", "clock", "notebook_display"]

COMPILE_NOTICE = ("compiling the model kernels (first run only; cached on disk for the next "
                  "runs)...")


def clock(seconds: float) -> str:
    """``42s``, ``3m05s``, ``2h07m``."""
    s = int(round(seconds))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


def _isatty(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def notebook_display() -> Any:
    """IPython's ``display`` module when this process is a Jupyter kernel (IPython already
    imported, its shell running a kernel), else None. Imports nothing that is not loaded."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return None
    try:
        shell = ipython.get_ipython()
    except Exception:                    # noqa: BLE001 - a broken IPython is no notebook
        return None
    if shell is None or getattr(shell, "kernel", None) is None:   # a terminal IPython
        return None
    try:
        from IPython import display
    except ImportError:                  # pragma: no cover - IPython without display
        return None
    return display


def _text(text: str) -> dict[str, str]:
    """``text`` as a plain-text output of a notebook (shown as it is, not as a repr)."""
    return {"text/plain": text}


class StatusLine:
    """One status line on ``stream`` (default stderr).

    ``tty`` (default: ``stream.isatty()``): redraw the line in place, at most every
    ``interval`` seconds. In a Jupyter notebook (``notebook``, default
    :func:`notebook_display` where neither ``stream`` nor ``tty`` is given; or an object
    with IPython's ``display(obj, raw=True, display_id=True) -> handle``, ``handle.update``)
    the line is one output updated in place, as often; where that display gives no
    handle, plain lines at every tenth of a known total, as in a log. Otherwise nothing
    is shown unless ``log``, and then a line is written at every tenth of the total given
    to :meth:`show`. ``enabled=False`` shows nothing at all (``--quiet``). ``header``: a
    line said once, terminal or not, when the work shows its first progress or notice (so
    a command refused in its checks prints only its error).
    """

    def __init__(self, stream: TextIO | None = None, *, tty: bool | None = None,
                 enabled: bool = True, log: bool = False, interval: float = 0.1,
                 header: str | None = None, notebook: Any = None) -> None:
        if notebook is None and stream is None and tty is None:
            notebook = notebook_display()
        self.stream = stream if stream is not None else sys.stderr
        self.notebook = notebook or None
        self.tty = False if self.notebook is not None else (
            _isatty(self.stream) if tty is None else bool(tty))
        self.enabled = bool(enabled)
        self.log = bool(log)
        self.interval = float(interval)
        self.header = header
        self._last = -float("inf")
        self._drawn = False
        self._next_tenth = 1
        self._handle: Any = None
        self._pending: str | None = None

    def begin(self) -> None:
        """Say the header, once (nothing when disabled or already said)."""
        if self.enabled and self.header is not None:
            header, self.header = self.header, None
            self.note(header)

    @property
    def active(self) -> bool:
        """Whether anything is shown at all."""
        return self.enabled and (self.tty or self.log or self.notebook is not None)

    def show(self, text: str, *, done: int | None = None, total: int | None = None,
             force: bool = False) -> None:
        """Show ``text`` (on a terminal or in a notebook: if ``interval`` has passed or
        ``force``; in a log: when ``done`` of ``total`` crosses a tenth, or ``force``)."""
        if not self.enabled:
            return
        self.begin()
        if self.notebook is not None:
            now = time.perf_counter()
            if force or now - self._last >= self.interval:
                self._last, self._pending = now, None
                self._update_notebook(text, done, total, force)
            else:
                self._pending = text             # shown by close(): the last state stays
        elif self.tty:
            now = time.perf_counter()
            if force or now - self._last >= self.interval:
                self._last = now
                self.stream.write("\r" + text + "\x1b[K")
                self.stream.flush()
                self._drawn = True
        elif self.log:
            self._log_line(text, done, total, force)

    def _log_line(self, text: str, done: int | None, total: int | None, force: bool) -> None:
        crossed = bool(total) and done is not None and done * 10 >= self._next_tenth * total
        if force or crossed:
            while total and done is not None and done * 10 >= self._next_tenth * total:
                self._next_tenth += 1
            self.stream.write(text + "\n")
            self.stream.flush()

    def _update_notebook(self, text: str, done: int | None, total: int | None,
                         force: bool) -> None:
        """The notebook's output updated to ``text`` (made by the first call); a display
        that gives no handle (an IPython without display ids) falls back to plain lines."""
        if self._handle is not None:
            self._handle.update(_text(text), raw=True)
            return
        handle = self.notebook.display(_text(text), raw=True, display_id=True)
        if handle is None or not hasattr(handle, "update"):
            self.notebook, self.log = None, True      # plain text from here on
            self._log_line(text, done, total, True)
            return
        self._handle = handle

    def note(self, text: str) -> None:
        """A line of its own (a notice), above the status line; shown unless disabled."""
        if not self.enabled:
            return
        if self.header is not None:
            self.begin()
        if self.tty and self._drawn:
            self.stream.write("\r\x1b[K")
            self._drawn = False
            self._last = -float("inf")
        self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        """End the status line (a newline after the last state on a terminal; in a
        notebook, the last state if it was not shown yet)."""
        if self.notebook is not None and self._handle is not None and self._pending is not None:
            self._handle.update(_text(self._pending), raw=True)
            self._pending = None
        if self.tty and self._drawn:
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False


class RunProgress(StatusLine):
    """Runs of a campaign: ``start(total, already, todo)``, ``update(result)`` per finished
    run (``result.ok``), ``close()``. Written to a log or pipe too, at every tenth."""

    def __init__(self, stream: TextIO | None = None, *, tty: bool | None = None,
                 enabled: bool = True, notebook: Any = None) -> None:
        super().__init__(stream, tty=tty, enabled=enabled, log=True, notebook=notebook)
        self.total = self.done = self.failed = self.todo = self.new = 0
        self.t0 = time.perf_counter()

    def start(self, total: int, already: int, todo: int) -> None:
        self.total, self.done, self.todo = total, already, todo
        self.t0 = time.perf_counter()
        self.show(self._line(), force=True)

    def update(self, result: Any) -> None:
        self.new += 1
        if result.ok:
            self.done += 1
        else:
            self.failed += 1
        self.show(self._line(), done=self.new, total=self.todo, force=self.new == self.todo
                  and self.tty)

    def _line(self) -> str:
        elapsed = time.perf_counter() - self.t0
        left = self.todo - self.new
        eta = "--"
        if self.new and left > 0:
            eta = clock(elapsed / self.new * left)
        elif left <= 0:
            eta = "0s"
        pct = 100.0 * self.done / self.total if self.total else 100.0
        return (f"runs {self.done}/{self.total} ({pct:.0f}%)  failures {self.failed}  "
                f"elapsed {clock(elapsed)}  ETA {eta}")


class SearchProgress(StatusLine):
    """An identification's progress, passed as its ``callback`` (called with the
    optimizer state after every iteration; never stops the run). ``prefix`` leads the
    line (e.g. ``"inspection 3/8: "``)."""

    def __init__(self, stream: TextIO | None = None, *, tty: bool | None = None,
                 enabled: bool = True, prefix: str = "", header: str | None = None,
                 notebook: Any = None) -> None:
        super().__init__(stream, tty=tty, enabled=enabled, header=header, notebook=notebook)
        self.prefix = prefix
        self.run = 1
        self._nfev = 0
        self._t0: float | None = None
        self._base = 0             # evaluations at the first iteration
        self._spent = 0            # evaluations of the finished runs

    def restart(self, prefix: str | None = None) -> None:
        """Count from here as a new identification (e.g. the next inspection), with a new
        ``prefix`` if given."""
        if prefix is not None:
            self.prefix = prefix
        self.run, self._nfev, self._t0, self._base, self._spent = 1, 0, None, 0, 0

    def __call__(self, state: Any) -> None:
        self.begin()
        if not self.active:
            return None
        now = time.perf_counter()
        nfev = int(state.nfev)
        if nfev < self._nfev:      # a new run (a restart, or the next seed)
            self.run += 1
            self._spent += self._nfev
        self._nfev = nfev
        if self._t0 is None:       # the rate counts from the first iteration on
            self._t0, self._base = now, nfev
        dt = now - self._t0
        rate = f"  {(self._spent + nfev - self._base) / dt:7.0f} evals/s" if dt > 0.05 else ""
        run = f"run {self.run}  " if self.run > 1 else ""
        self.show(f"{self.prefix}{run}iteration {state.nit:4d}  best fitness {state.best_f:.4e}  "
                  f"{nfev:6d} evaluations{rate}")
        return None


class CountProgress(StatusLine):
    """Steps of a loop: ``update(i, n)`` shows ``"{what} i/n{noun}, elapsed"`` (``n``
    None: no total; ``noun`` what is counted, e.g. ``" model runs"``)."""

    def __init__(self, what: str, stream: TextIO | None = None, *, tty: bool | None = None,
                 enabled: bool = True, noun: str = "", header: str | None = None,
                 notebook: Any = None) -> None:
        super().__init__(stream, tty=tty, enabled=enabled, header=header, notebook=notebook)
        self.what = what
        self.noun = noun
        self.t0 = time.perf_counter()

    def update(self, i: int, n: int | None = None) -> None:
        self.begin()
        count = f"{i}/{n}" if n else f"{i}"
        self.show(f"{self.what} {count}{self.noun}, {clock(time.perf_counter() - self.t0)}",
                  force=bool(n) and i >= n)


_NOTICE_SAID = False


@contextlib.contextmanager
def compile_notice(line: StatusLine | None = None, *, enabled: bool = True) -> Iterator[None]:
    """Within the block, say :data:`COMPILE_NOTICE` (through ``line``'s :meth:`~StatusLine.note`,
    or on stderr) the first time in this process that Numba starts compiling a kernel, before
    it does; a kernel loaded from Numba's disk cache says nothing. At most once per process."""
    if not enabled or _NOTICE_SAID:
        yield
        return
    try:
        from numba.core import event
    except ImportError:                  # pragma: no cover - numba is a dependency
        yield
        return

    class _Notice(event.Listener):
        def on_start(self, ev: Any) -> None:
            global _NOTICE_SAID
            if _NOTICE_SAID:
                return
            _NOTICE_SAID = True
            if line is not None:
                line.note(COMPILE_NOTICE)
            else:
                sys.stderr.write(COMPILE_NOTICE + "\n")
                sys.stderr.flush()

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", _Notice()):
        yield
