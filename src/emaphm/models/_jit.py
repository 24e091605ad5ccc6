"""The one place that decides how model kernels are compiled, and where they are cached.

Kernels are compiled in nopython mode and cached on disk, so that a warm process
(or a worker of a campaign) pays no compile time. Numba's own cache checks only
the file that defines a kernel: a kernel that calls or inlines a physics function
from another module (the transmission step, the winding step...) or reads a
module constant (the layout's column numbers) keeps its old machine code when
only that other module changes (numba issues #1833, #6845). After an upgrade or
a ``git pull`` over an editable install, that would be the old physics, silently.

So every kernel of this package is cached under a directory named by a digest of
the package's sources (:data:`SOURCES_DIGEST`, every ``*.py`` of
``emaphm.models``): a change to any of them starts a fresh cache, and the old one
is never read again. The directory (:data:`CACHE_DIR`) is the first writable of
``$EMAPHM_CACHE_DIR``, the package's own ``__pycache__`` and the user's cache
(``$XDG_CACHE_HOME`` or ``~/.cache``, ``emaphm``); with none writable, kernels are
compiled in every process. Numba's ``NUMBA_CACHE_DIR`` of other libraries is left
as it is: it is switched only while this package's kernels are declared.

Each edit of the model sources leaves a directory behind, tens of megabytes after a few
pulls. On import, :func:`prune_stale` removes the stale ones beside
:data:`CACHE_DIR`: it keeps the current one and the most recently used other one (a second
installed version, or the checkout a running campaign was started from), and any used in
the last hour; it touches nothing but directories named ``kernels-<16 hex digits>``
directly in that folder (never a link, never outside it), and two processes pruning at
once do not trip over each other.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import time
import types
from pathlib import Path
from typing import Any, Callable, Iterator

import numba
from numba import njit

_HERE = Path(__file__).resolve().parent


def sources_digest(folder: Path = _HERE) -> str:
    """A digest (16 hex digits) of every ``*.py`` in ``folder``, names and contents."""
    h = hashlib.sha256()
    for path in sorted(folder.glob("*.py")):
        h.update(path.name.encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


#: Digest of the model sources the kernels are compiled from.
SOURCES_DIGEST = sources_digest()


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
        return True
    except OSError:
        return False


def cache_dir(digest: str = SOURCES_DIGEST) -> Path | None:
    """Where kernels compiled from sources of ``digest`` are cached (None: nowhere)."""
    candidates = []
    if os.environ.get("EMAPHM_CACHE_DIR"):
        candidates.append(Path(os.environ["EMAPHM_CACHE_DIR"]))
    candidates.append(_HERE / "__pycache__")
    xdg = os.environ.get("XDG_CACHE_HOME")
    candidates.append((Path(xdg) if xdg else Path.home() / ".cache") / "emaphm")
    for base in candidates:
        folder = base / f"kernels-{digest}"
        if _writable(folder):
            return folder
    return None


#: Directory of this package's kernel cache (None: not cached).
CACHE_DIR = cache_dir()

#: Stale kernel caches that :func:`prune_stale` keeps: the most recently used ones, and
#: any used within this many seconds.
KEEP_OTHERS = 1
MIN_AGE_S = 3600.0
_KERNELS = re.compile(r"kernels-[0-9a-f]{16}")
_DOOMED = re.compile(r"\.stale-kernels-[0-9a-f]{16}-\d+")


def _last_used(folder: Path) -> float:
    """The newest modification time of ``folder`` and its entries (Numba writes its index
    and object files there)."""
    times = [folder.lstat().st_mtime]
    with os.scandir(folder) as entries:
        times += [e.stat(follow_symlinks=False).st_mtime for e in entries]
    return max(times)


def prune_stale(root: Path, current: str = SOURCES_DIGEST, *, keep_others: int = KEEP_OTHERS,
                min_age_s: float = MIN_AGE_S, now: float | None = None) -> list[str]:
    """Remove from ``root`` the kernel caches of model sources other than ``current`` (all
    but the ``keep_others`` most recently used, and only those unused for ``min_age_s``
    seconds); return the names removed.

    Only directories directly in ``root`` named ``kernels-<16 hex digits>`` are candidates
    (a link of that name is left alone, and so is what it points to). Each is first renamed
    to ``.stale-kernels-<digest>-<pid>`` (atomic: of two processes pruning at once one
    wins, the other moves on) and then deleted; a removal left half done (a file in use) is
    finished by a later prune. Errors are never raised: a cache that cannot be pruned is
    only a cache."""
    now = time.time() if now is None else now
    stale = []
    try:
        with os.scandir(root) as entries:
            for e in entries:
                if _DOOMED.fullmatch(e.name) and e.is_dir(follow_symlinks=False):
                    shutil.rmtree(e.path, ignore_errors=True)
                elif (_KERNELS.fullmatch(e.name) and e.name != f"kernels-{current}"
                      and e.is_dir(follow_symlinks=False)):
                    with contextlib.suppress(OSError):
                        stale.append((_last_used(Path(e.path)), e.name))
    except OSError:
        return []
    stale.sort(reverse=True)
    removed = []
    for used, name in stale[max(keep_others, 0):]:
        if now - used < min_age_s:
            continue
        doomed = Path(root) / f".stale-{name}-{os.getpid()}"
        try:
            os.rename(Path(root) / name, doomed)
        except OSError:                 # gone already (another process), or not ours to move
            continue
        shutil.rmtree(doomed, ignore_errors=True)
        removed.append(name)
    return removed


if CACHE_DIR is not None:
    prune_stale(CACHE_DIR.parent)


@contextlib.contextmanager
def _cache_location() -> Iterator[None]:
    """Numba's cache directory set to :data:`CACHE_DIR` while a kernel is declared (its
    cache locator is chosen then), restored after."""
    old = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(CACHE_DIR)
    try:
        yield
    finally:
        numba.config.CACHE_DIR = old


def cached_njit(**options: Any) -> Callable[[Callable], Any]:
    """``numba.njit(**options)``, cached under :data:`CACHE_DIR` (not cached without one)."""
    def decorate(func: Callable) -> Any:
        if CACHE_DIR is None:
            return njit(**options)(func)
        with _cache_location():
            return njit(cache=True, **options)(func)
    return decorate


#: Compile a scalar physics function or a kernel: nopython, cached (:func:`cached_njit`).
jit = cached_njit(nogil=True)


def specialised(func: Callable, name: str, compile_with: Callable[[Callable], Any],
                **globals_: Any) -> Any:
    """``func``'s code under ``name``, compiled by ``compile_with`` (a :func:`cached_njit`),
    with the named globals it calls replaced: one variant of a kernel, compiled the first
    time it is called and cached apart from the others (under its own name)."""
    g = dict(func.__globals__)
    g.update(globals_)
    f = types.FunctionType(func.__code__, g, name, func.__defaults__, func.__closure__)
    f.__qualname__ = name
    f.__doc__ = func.__doc__
    return compile_with(f)


def variants(body: Callable, compile_with: Callable[[Callable], Any],
             drive: dict[bool, dict[str, Any]], inverter: dict[bool, dict[str, Any]]) -> dict:
    """The compiled variants of a kernel's loop ``body`` by ``(plain drive, ideal
    inverter)`` (:func:`emaphm.models._monitoring_common.variant_key`): ``drive[plain]`` and
    ``inverter[ideal]`` name the steps each swaps in (:func:`specialised`), each cached as
    ``<body's name without _body>_<plain|options>_<ideal|dead_time>``."""
    stem = body.__name__.removesuffix("_body")
    return {(plain, ideal): specialised(
        body, f"{stem}_{'plain' if plain else 'options'}_{'ideal' if ideal else 'dead_time'}",
        compile_with, **drive[plain], **inverter[ideal])
        for plain in (True, False) for ideal in (True, False)}
