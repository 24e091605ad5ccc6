"""Binary bench exports are read in a child process, the *sandbox*: a long-lived Python
process that runs the format's reader (scipy.io, h5py, npTDMS, asammdf, pyarrow) and
answers over a pipe. A library that crashes on a damaged file (scipy's ``loadmat`` dies
of SIGSEGV on one flipped byte of a MAT file) takes down the child, not the command:
the crash, a hang past :data:`READ_TIMEOUT` or any exception the library raises becomes
a :class:`~emaphm.traces.TraceError` that names the file and the cause, and the next file
gets a fresh child. One child serves every file a process reads (started on the first,
restarted after a crash), so that reading many files costs one start-up, not one each.

The protocol is a pickled request and a pickled reply per call, each behind its length:
``open`` (a reader class on a path: its :class:`~.base.SourceInfo`), ``blocks`` (start
reading channels), ``next`` (the next :class:`~.base.Block`, or None at the end) and
``close``. The child trusts its parent; the parent trusts the child's replies, which
its own code makes.
"""

from __future__ import annotations

import atexit
import importlib
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import replace
from pathlib import Path

from ..container import TraceError, TraceWarning
from .base import Block, ChannelInfo, MissingReaderError, SourceInfo, cause, read_path
from .channel_map import MapError, SourceOptions

__all__ = ["READ_TIMEOUT", "ReaderProcess", "SandboxedSource", "reader_process", "serve"]

#: Seconds one call of the sandbox may take (opening a file, reading one block) before
#: the child is killed and the file refused as damaged.
READ_TIMEOUT = 300.0

_LENGTH = struct.Struct("<Q")
#: Errors the child sends back as they are (anything else is the file's damage).
_PASSED = {"TraceError": TraceError, "MissingReaderError": MissingReaderError,
           "MapError": MapError, "FileNotFoundError": FileNotFoundError}


class _ChildGone(Exception):
    """The child died, closed its pipe, or did not answer in time."""


# ----------------------------------------------------------------------------- framing
def _send(fd: int, message: object) -> None:
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(_LENGTH.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _recv(fd: int, deadline: float | None = None) -> object:
    """One message from ``fd``; _ChildGone at end of file or past ``deadline``."""
    head = _read_exactly(fd, _LENGTH.size, deadline)
    return pickle.loads(_read_exactly(fd, _LENGTH.unpack(head)[0], deadline))


def _read_exactly(fd: int, n: int, deadline: float | None) -> bytearray:
    buf = bytearray(n)
    view = memoryview(buf)
    got = 0
    while got < n:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise _ChildGone("timeout")
        k = os.readv(fd, [view[got:got + (1 << 24)]])
        if k == 0:
            raise _ChildGone("end of file")
        got += k
    return buf


# ----------------------------------------------------------------------------- the child
def serve(rfd: int, wfd: int) -> None:
    """The child's loop: answer requests from ``rfd`` on ``wfd`` until the parent closes
    its end. Library noise (warnings, logging, what a destructor prints on stderr) goes
    nowhere; a :class:`~emaphm.traces.TraceWarning` of a reader goes back to the parent."""
    import logging

    signal.signal(signal.SIGINT, signal.SIG_IGN)     # the parent handles Ctrl-C
    logging.disable(logging.CRITICAL)
    sources: dict[int, object] = {}
    readers: dict[int, Iterator[Block]] = {}
    while True:
        try:
            request = _recv(rfd)
        except _ChildGone:
            return
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("ignore")
            warnings.simplefilter("always", TraceWarning)
            try:
                reply = ("ok", _handle(request, sources, readers))
            except BaseException as exc:             # noqa: BLE001 - the file's damage, sent back
                reply = _error(exc)
        said = [str(w.message) for w in seen if issubclass(w.category, TraceWarning)]
        _send(wfd, reply + (said,))


def _handle(request: tuple, sources: dict, readers: dict) -> object:
    what, key, *args = request
    if what == "open":
        module, cls, path, options, cwd = args
        if os.getcwd() != cwd:                       # the parent's, for its relative paths
            try:
                os.chdir(cwd)
            except OSError:
                path = os.path.join(cwd, path)
        reader = getattr(importlib.import_module(module), cls)
        sources[key] = reader(path, options)
        return sources[key].info
    if what == "blocks":
        channels, first, stop = args
        readers[key] = iter(sources[key].blocks(channels, first, stop))
        return None
    if what == "next":
        return next(readers[key], None)
    readers.pop(key, None)                           # close
    source = sources.pop(key, None)
    if source is not None:
        source.close()
    return None


def _error(exc: BaseException) -> tuple:
    name = type(exc).__name__
    if name in _PASSED and isinstance(exc, _PASSED[name]):
        return ("error", (name, str(exc)))
    if isinstance(exc, MemoryError):
        return ("error", ("memory", ""))
    return ("error", ("damage", cause(exc, 300)))


# ----------------------------------------------------------------------------- the parent
def _signal_name(code: int) -> str:
    try:
        name = signal.Signals(-code).name
    except ValueError:
        return f"exit status {code}"
    return name + (", perhaps out of memory" if name == "SIGKILL" else "")


class ReaderProcess:
    """The child that reads, started on first use and after a crash; ``timeout``: seconds
    a call may take (default :data:`READ_TIMEOUT`). Calls are serialised (a lock)."""

    def __init__(self, timeout: float | None = None) -> None:
        self.timeout = timeout
        self.lock = threading.RLock()
        self.proc: subprocess.Popen | None = None
        self.fds: tuple[int, int] | None = None
        self.owner = 0
        self.generation = 0
        self.keys = 0

    def _start(self) -> None:
        to_child, request_w = os.pipe()
        reply_r, from_child = os.pipe()
        src = str(Path(__file__).resolve().parents[3])
        path = os.environ.get("PYTHONPATH")
        env = {**os.environ, "PYTHONPATH": src + (os.pathsep + path if path else "")}
        code = ("import sys\nfrom emaphm.traces.importers.sandbox import serve\n"
                "serve(int(sys.argv[1]), int(sys.argv[2]))")
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-c", code, str(to_child), str(from_child)],
                pass_fds=(to_child, from_child), stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                start_new_session=True)
        except BaseException:
            for fd in (to_child, request_w, reply_r, from_child):
                os.close(fd)
            raise
        os.close(to_child)
        os.close(from_child)
        self.fds = (request_w, reply_r)
        self.owner = os.getpid()
        self.generation += 1

    def stop(self) -> None:
        """End the child (it is started again on the next call)."""
        with self.lock:
            proc, fds = self.proc, self.fds
            self.proc = self.fds = None
            if fds is not None and self.owner == os.getpid():
                for fd in fds:
                    os.close(fd)
            if proc is not None and self.owner == os.getpid():
                if proc.poll() is None:
                    proc.kill()
                proc.wait()

    def forget(self) -> None:
        """In a forked child: the parent's child and pipes are not this process's."""
        if self.fds is not None:
            for fd in self.fds:
                os.close(fd)
        self.proc = self.fds = None
        self.lock = threading.RLock()

    def call(self, request: tuple, path: Path, what: str) -> tuple[object, int]:
        """Send ``request`` about ``path`` (a file of ``what``); its answer and the child's
        generation, or the error the child met (a crash or a hang as a TraceError)."""
        with self.lock:
            if self.proc is None or self.proc.poll() is not None:
                self.stop()
                self._start()
            assert self.fds is not None and self.proc is not None
            limit = READ_TIMEOUT if self.timeout is None else self.timeout
            try:
                _send(self.fds[0], request)
                reply = _recv(self.fds[1], time.monotonic() + limit)
            except (_ChildGone, BrokenPipeError) as exc:
                timed_out = isinstance(exc, _ChildGone) and str(exc) == "timeout"
                proc = self.proc
                self.stop()
                raise TraceError(_gone(path, what, limit if timed_out else None,
                                       proc.returncode)) from None
            except BaseException:                # interrupted mid-call: out of step, restart
                self.stop()
                raise
            status, value, said = reply         # type: ignore[misc]
            for text in said:
                warnings.warn(TraceWarning(text), stacklevel=4)
            if status == "error":
                raise _raised(*value, path=path, what=what)
            return value, self.generation

    def new_key(self) -> int:
        with self.lock:
            self.keys += 1
            return self.keys


def _gone(path: Path, what: str, timeout: float | None, code: int | None) -> str:
    if timeout is not None:
        return (f"{path}: reading it as {what} took more than {timeout:g} s and was stopped; "
                "the file is damaged (or far larger than it looks): export it again")
    how = _signal_name(code) if code is not None and code < 0 else "it stopped"
    return (f"{path}: reading it as {what} crashed the reader ({how}); the file is damaged "
            f"or is not {what}: export it again")


def _raised(kind: str, text: str, *, path: Path, what: str) -> Exception:
    """The exception the child's error ``kind`` (with its ``text``) is in this process."""
    if kind in _PASSED:
        return _PASSED[kind](text)
    if kind == "memory":
        return TraceError(f"{path}: reading it as {what} needs more memory than this machine "
                          "has; the file is damaged (a length that does not add up) or too "
                          "large: export a shorter part")
    return TraceError(f"{path}: cannot be read as {what}, it is damaged or is not one "
                      f"({text}); export it again")


_SHARED: ReaderProcess | None = None
_SHARED_LOCK = threading.Lock()


def reader_process() -> ReaderProcess:
    """The process-wide sandbox (one child for every file read)."""
    global _SHARED
    with _SHARED_LOCK:
        if _SHARED is None:
            _SHARED = ReaderProcess()
            atexit.register(_SHARED.stop)
            os.register_at_fork(after_in_child=_SHARED.forget)
        return _SHARED


class SandboxedSource:
    """A :class:`~.base.Source` whose reader (``module``'s ``cls``) runs in the sandbox
    (``process``, default the shared one); ``what`` names the format in refusals (``"a
    MATLAB file"``)."""

    def __init__(self, path: str | Path, module: str, cls: str, what: str,
                 options: SourceOptions = SourceOptions(),
                 process: ReaderProcess | None = None) -> None:
        self.path = read_path(path)
        self.what = what
        self.process = process or reader_process()
        self.key = self.process.new_key()
        info, self.generation = self.process.call(
            ("open", self.key, module, cls, str(self.path), options, os.getcwd()),
            self.path, what)
        assert isinstance(info, SourceInfo)
        self.info = replace(info, path=Path(path)) if info.path != Path(path) else info
        self.closed = False

    def _call(self, request: tuple) -> object:
        if self.process.generation != self.generation:
            raise TraceError(f"{self.path}: the reader of {self.what} was restarted while the "
                             "file was open; read it again")
        return self.process.call(request, self.path, self.what)[0]

    def blocks(self, channels: Sequence[ChannelInfo], first: int = 0,
               stop: int | None = None) -> Iterator[Block]:
        self._call(("blocks", self.key, tuple(channels), first, stop))
        while (block := self._call(("next", self.key))) is not None:
            yield block                             # type: ignore[misc]

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if self.process.generation == self.generation and self.process.proc is not None:
            self.process.call(("close", self.key), self.path, self.what)
